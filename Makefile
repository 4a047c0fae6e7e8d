# The two commands of the README: `make demo` and `make test`. Both install what is missing
# (scripts/install-deps.sh), configure and build Release in build/release.
BUILD ?= build/release
JOBS ?= $(shell nproc)
# Haswell-level x86 (AVX2, FMA): every machine we build on has it, and one instruction set
# gives the same bits everywhere, which the committed state hashes rely on (docs/design.md).
MARCH ?= x86-64-v3
CMAKE_ARGS ?=
DEMO_SCENE ?= scenes/default.json
DEMO_OUT ?= out/default

# The sanitizer build (AddressSanitizer + UndefinedBehaviorSanitizer, CPU only, own folder).
ASAN_BUILD ?= build/asan
# Assimp leaks inside its own loaders on some malformed files (tests/lsan.supp).
ASAN_ENV = ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 SPHFEM_FUZZ_SLOW=20
# What CI runs under the sanitizers (the whole suite takes hours there): the readers, their fuzz
# tests, the limits, the output failures, and short runs of fluid and bodies coupled.
ASAN_QUICK = FuzzReaders|SceneLimits|SceneErrors|SceneLoad|FemImport|IoFrame|IoSeries|RunInfo|CliOutput|Cli\.RunWritesFrames|Cli\.RunOfABodyScene|SimBodiesWithFluid
# Left out: the surface reader's mutations reach an Assimp loader that asks for 64 GiB, which
# the sanitizer's allocator aborts on (a release build gets std::bad_alloc and refuses the
# file); how many mutations run depends on the machine's speed, so it would fail at random.
ASAN_QUICK_EXCLUDE = FuzzReaders\.SeededMutationsAreReadOrRefusedCleanly/surface

.PHONY: deps assets configure build demo test bench clean asan-build test-asan test-asan-quick

deps:
	@bash scripts/install-deps.sh

# The bunny of the paper's scenes (scenes/paper/bunny.json, dragon.json), from the npm registry;
# a machine without npm still builds and tests, and those two scenes say what is missing.
assets:
	@bash scripts/fetch-bunny.sh build/assets || echo "note: the bunny mesh was not fetched (scenes/paper/bunny.json and dragon.json need it)"

configure: deps assets
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DSPHFEM_MARCH=$(MARCH) -DSPHFEM_ENABLE_GL=ON $(CMAKE_ARGS) >/dev/null

build: configure
	@cmake --build $(BUILD) -j$(JOBS)

demo: build
	$(BUILD)/bin/sphfem run $(DEMO_SCENE) --out $(DEMO_OUT)
	$(BUILD)/bin/sphfem render $(DEMO_OUT) --frames last

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

asan-build: deps
	@cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Debug -DSPHFEM_SANITIZE=ON -DSPHFEM_ENABLE_CUDA=OFF -DSPHFEM_ENABLE_GL=OFF >/dev/null
	@cmake --build $(ASAN_BUILD) -j$(JOBS) --target sphfem_tests sphfem_cli

# The whole suite under the sanitizers: any report fails its test.
test-asan: asan-build
	$(ASAN_ENV) ctest --test-dir $(ASAN_BUILD) --output-on-failure -j$(JOBS)

test-asan-quick: asan-build
	$(ASAN_ENV) ctest --test-dir $(ASAN_BUILD) --output-on-failure -j$(JOBS) -R '$(ASAN_QUICK)' \
	  -E '$(ASAN_QUICK_EXCLUDE)'

bench: build
	$(BUILD)/bin/sphfem bench --out bench/results

clean:
	rm -rf $(BUILD)
