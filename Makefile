# Convenience front end to CMake. The two commands of the README:
#   make demo   install what is missing, build, run karst on the default scenario
#   make test   install what is missing, build Debian's ParaView chroot for the ParaView test
#               once (scripts/paraview-chroot; a complete one is kept), build with -Werror,
#               run the tests, then build with AddressSanitizer + UndefinedBehaviorSanitizer
#               and run them again, then run every libFuzzer target for a bounded time (make fuzz)
JOBS     ?= $(shell nproc)
BUILD    ?= build
ASAN     ?= build-asan
FUZZ     ?= build-fuzz
# Seconds of fuzzing per target in make fuzz (tests/fuzz/run.sh, docs/fuzzing.md).
FUZZ_SECONDS ?= 20
SCENARIO ?= datasets/scenarios/branchwork.yaml
DEMO_OUT ?= out/branchwork

.PHONY: all deps paraview-chroot build demo test test-fast test-asan fuzz bench clean format

all: build

deps:
	scripts/install-deps

# Debian's ParaView beside python3-vtk9 (they conflict): tests/cli/test_paraview.sh runs it here.
paraview-chroot: deps
	scripts/paraview-chroot build

$(BUILD)/Makefile:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DKARST_WERROR=ON

build: $(BUILD)/Makefile
	cmake --build $(BUILD) -j $(JOBS)

demo: deps build
	$(BUILD)/karst validate $(SCENARIO)
	$(BUILD)/karst generate $(SCENARIO) -o $(DEMO_OUT) --samples
	$(BUILD)/karst metrics $(DEMO_OUT)/network.vtp --observed
	@echo
	@echo "The network is in $(DEMO_OUT)/: view it in ParaView with '$(BUILD)/karst view $(DEMO_OUT)'"
	@echo "(tunnel types, node kinds and units named; or open $(DEMO_OUT)/network.vtp by hand);"
	@echo "$(DEMO_OUT)/samples.vtp holds the sample cloud, $(DEMO_OUT)/run.json every parameter and timing."
	@echo "Python: PYTHONPATH=$(CURDIR)/$(BUILD)/python /usr/bin/python3 -c 'import karst' (docs/python.md)."

test-fast: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

$(ASAN)/Makefile:
	cmake -S . -B $(ASAN) -DCMAKE_BUILD_TYPE=Debug -DKARST_WERROR=ON -DKARST_SANITIZE=ON -DKARST_BUILD_BENCH=OFF

test-asan: $(ASAN)/Makefile
	cmake --build $(ASAN) -j $(JOBS)
	cd $(ASAN) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS)

# libFuzzer targets of tests/fuzz/ (clang, ASan + UBSan): build them, run each for
# FUZZ_SECONDS, fail on any crash, leak, timeout or out-of-memory.
$(FUZZ)/Makefile:
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKARST_WERROR=ON \
	  -DKARST_FUZZ=ON -DKARST_BUILD_TESTS=OFF -DKARST_BUILD_BENCH=OFF -DKARST_WITH_PYTHON=OFF \
	  -DKARST_WITH_MPI=OFF -DBUILD_SHARED_LIBS=OFF

fuzz: deps $(FUZZ)/Makefile
	cmake --build $(FUZZ) -j $(JOBS) --target karst_fuzz_targets
	FUZZ_SECONDS=$(FUZZ_SECONDS) tests/fuzz/run.sh $(FUZZ)

test: paraview-chroot
	$(MAKE) test-fast
	$(MAKE) test-asan
	$(MAKE) fuzz

bench: build
	cmake --build $(BUILD) --target bench -j $(JOBS)

format:
	clang-format -i $$(git ls-files '*.c' '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(ASAN) $(FUZZ)
