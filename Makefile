# Convenience front end to CMake. The two commands of the README:
#   make demo   install what is missing, build, run karst on the default scenario
#   make test   install what is missing, build with -Werror, run the tests, then
#               build with AddressSanitizer + UndefinedBehaviorSanitizer and run them again
JOBS     ?= $(shell nproc)
BUILD    ?= build
ASAN     ?= build-asan
SCENARIO ?= datasets/scenarios/branchwork.yaml
DEMO_OUT ?= out/branchwork

.PHONY: all deps build demo test test-fast test-asan bench clean format

all: build

deps:
	scripts/install-deps

$(BUILD)/Makefile:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DKARST_WERROR=ON

build: $(BUILD)/Makefile
	cmake --build $(BUILD) -j $(JOBS)

demo: deps build
	$(BUILD)/karst validate $(SCENARIO)
	$(BUILD)/karst generate $(SCENARIO) -o $(DEMO_OUT) --samples
	$(BUILD)/karst metrics $(DEMO_OUT)/network.vtp --observed
	@echo
	@echo "The network is in $(DEMO_OUT)/: open $(DEMO_OUT)/network.vtp in ParaView"
	@echo "(File > Open, Apply, then colour by tunnel_type, radius or kind);"
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

test: deps
	$(MAKE) test-fast
	$(MAKE) test-asan

bench: build
	cmake --build $(BUILD) --target bench -j $(JOBS)

format:
	clang-format -i $$(git ls-files '*.c' '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(ASAN)
