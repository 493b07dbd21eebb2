# The two commands of README.md:
#   make run   installs every dependency, builds, runs the main job
#   make test  installs every dependency, builds, runs the tests
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
CMAKE_ARGS ?=

.PHONY: run test deps build bench config-doc clean

deps:
	bash scripts/install-deps.sh

$(BUILD_DIR)/CMakeCache.txt:
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: deps $(BUILD_DIR)/CMakeCache.txt
	cmake --build $(BUILD_DIR) -j $(JOBS)

run: build
	bash scripts/run-main.sh $(BUILD_DIR)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

bench: build
	bash scripts/run-benchmarks.sh $(BUILD_DIR)

# docs/config.md, the list of every setting (a test compares it with the code).
config-doc: build
	$(BUILD_DIR)/apps/comorph config keys --markdown > docs/config.md

clean:
	rm -rf $(BUILD_DIR)
