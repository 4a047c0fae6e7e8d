# The installed package as another project sees it: `cmake --install` into a fresh prefix,
# then (1) every installed header compiles on its own against that prefix and the system, and
# (2) examples/embed configures with find_package(sphfem), builds and runs a scene.
# cmake -DBUILD_DIR=<build> -DSOURCE_DIR=<source> -DWORK=<scratch folder> -P this file
foreach(v BUILD_DIR SOURCE_DIR WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "embed_example_test: pass -D${v}=...")
  endif()
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK})
set(prefix ${WORK}/prefix)
run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

# One translation unit per installed header, each including only that header.
file(GLOB_RECURSE headers RELATIVE ${prefix}/include ${prefix}/include/sphfem/*.h)
list(LENGTH headers n)
if(n LESS 20)
  message(FATAL_ERROR "only ${n} headers installed under ${prefix}/include")
endif()
set(check ${WORK}/headers)
set(sources "")
foreach(h ${headers})
  string(MAKE_C_IDENTIFIER ${h} name)
  file(WRITE ${check}/${name}.cpp "#include <${h}>\n")
  list(APPEND sources ${name}.cpp)
endforeach()
file(WRITE ${check}/CMakeLists.txt "cmake_minimum_required(VERSION 3.25)
project(header_check LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 17)
find_package(sphfem REQUIRED)
add_library(header_check OBJECT ${sources})
target_link_libraries(header_check PRIVATE sphfem::sphfem)
")
run("configure the header check" ${CMAKE_COMMAND} -S ${check} -B ${check}/build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Debug)
run("compile every installed header alone" ${CMAKE_COMMAND} --build ${check}/build -j2)

set(embed ${WORK}/embed)
run("configure examples/embed" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/embed -B ${embed}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run("build examples/embed" ${CMAKE_COMMAND} --build ${embed} -j2)
run("run examples/embed" ${embed}/embed ${SOURCE_DIR}/scenes/dam_break.json 0.01)
message("${last_output}")
if(NOT last_output MATCHES "particles, highest at y = ")
  message(FATAL_ERROR "examples/embed printed no particles:\n${last_output}")
endif()
file(REMOVE_RECURSE ${WORK})
