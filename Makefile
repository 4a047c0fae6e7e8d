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
# What CI runs under the sanitizers (the whole suite takes an hour or more, see test-asan): the readers, their fuzz
# tests, the limits, the output failures, and short runs of fluid and bodies coupled.
ASAN_QUICK = FuzzReaders|SceneLimits|SceneErrors|SceneLoad|FemImport|IoFrame|IoSeries|RunInfo|CliOutput|Cli\.RunWritesFrames|Cli\.RunOfABodyScene|SimBodiesWithFluid|/CoupleMethods\.
# /CoupleMethods. is the momentum test of the three couplings (77 s for the three under the
# sanitizers on two cores); CoupleMethodsPaper, every paper scene under both couplings (it
# passes there in 288 s), is left to make test-asan.

# The readers' libFuzzer targets (fuzz/README.md): clang, coverage and the sanitizers, own folder.
FUZZ_BUILD ?= build/fuzz
FUZZ_SECONDS ?= 60
FUZZ_READERS = scene surface tetgen gmsh checkpoint run_info vtu ply

.PHONY: deps assets configure build demo test bench clean asan-build test-asan test-asan-quick \
	fuzz-build fuzz

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

# The whole suite under the sanitizers: any report fails its test. About 2 hours of test time
# (an hour on two idle cores); ASAN_TESTS (a ctest regex) runs a part, e.g. the parameterised
# suites '/'. Its results: docs/validation.md, "The whole suite under the sanitizers".
ASAN_TESTS ?= .
test-asan: asan-build
	$(ASAN_ENV) ctest --test-dir $(ASAN_BUILD) --output-on-failure -j$(JOBS) -R '$(ASAN_TESTS)'

test-asan-quick: asan-build
	$(ASAN_ENV) ctest --test-dir $(ASAN_BUILD) --output-on-failure -j$(JOBS) -R '$(ASAN_QUICK)'

fuzz-build:
	@bash scripts/install-deps.sh --fuzz
	@CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DSPHFEM_FUZZ=ON -DSPHFEM_ENABLE_CUDA=OFF -DSPHFEM_ENABLE_GL=OFF -DSPHFEM_BUILD_TESTS=OFF >/dev/null
	@cmake --build $(FUZZ_BUILD) -j$(JOBS) --target $(addprefix fuzz_,$(FUZZ_READERS))

# Each reader's libFuzzer target for FUZZ_SECONDS, from its seeds and past findings
# (tests/data/fuzz/<reader>/) and the corpus of earlier runs ($(FUZZ_BUILD)/corpus/<reader>).
# A finding leaves its input and log in $(FUZZ_BUILD)/findings/<reader>/; all readers run, then
# the target fails if any found something.
fuzz: fuzz-build
	@failed=""; for r in $(FUZZ_READERS); do \
	  mkdir -p $(FUZZ_BUILD)/corpus/$$r $(FUZZ_BUILD)/findings/$$r; \
	  if $(ASAN_ENV) $(FUZZ_BUILD)/fuzz/fuzz_$$r $(FUZZ_BUILD)/corpus/$$r tests/data/fuzz/$$r \
	       -max_total_time=$(FUZZ_SECONDS) -timeout=20 -rss_limit_mb=4096 -print_final_stats=1 \
	       -artifact_prefix=$(FUZZ_BUILD)/findings/$$r/ >$(FUZZ_BUILD)/findings/$$r/log.txt 2>&1; then \
	    echo "fuzz_$$r: $$(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' \
	      $(FUZZ_BUILD)/findings/$$r/log.txt | grep -o '[0-9]*$$') inputs in $(FUZZ_SECONDS) s, nothing found"; \
	  else \
	    echo "fuzz_$$r: FOUND a defect, see $(FUZZ_BUILD)/findings/$$r/"; failed="$$failed $$r"; \
	  fi; \
	done; \
	[ -z "$$failed" ] || { echo "fuzz: findings in$$failed (fuzz/README.md says what to do)"; exit 1; }

bench: build
	$(BUILD)/bin/sphfem bench --out bench/results

clean:
	rm -rf $(BUILD)
