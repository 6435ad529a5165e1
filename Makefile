# meso: `make demo` and `make test` do all the set-up on a fresh Debian machine.
BUILD ?= build
BUILD_ASAN ?= build-asan
BUILD_CLANG ?= build-clang
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps build demo test test-assets test-views test-slurm test-asan test-clang bench \
	install clean format format-check docs-check python

all: build

deps:
	@bash scripts/install-deps.sh

# The build is quiet unless asked (make VERBOSE=1, which CMake's makefiles also read: every
# command in full): its progress lines on stdout go nowhere, its warnings and errors (stderr)
# still show, so `make demo` starts with pictures, not ~830 lines of build.
ifeq ($(VERBOSE),)
QUIET := >/dev/null
endif

$(BUILD)/CMakeCache.txt: | deps
	@echo "make: configuring and building meso in $(BUILD)/ (about 1.5 min the first time; make VERBOSE=1 shows every step)"
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) $(QUIET)

build: deps $(BUILD)/CMakeCache.txt
	@cmake --build $(BUILD) -j $(JOBS) $(QUIET)

# The Python package (docs/python.md) in $(BUILD)/python, over $(BUILD)/libmeso.so: what the
# tests import (PYTHONPATH=$(BUILD)/python). `make build` makes it too, unless -DMESO_PYTHON=OFF.
python: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS) --target meso_python
	@echo "make python: PYTHONPATH=$(CURDIR)/$(BUILD)/python /usr/bin/python3 -c 'import meso'"

demo: build
	$(BUILD)/meso demo -o demo

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# Meshes nobody here made: assimp's test corpus through meso info and every technique against
# the reference, at 64 x 64 (scripts/test-assets.sh; docs/techniques.md). CI runs it.
test-assets: build
	bash scripts/test-assets.sh $(BUILD)/meso

# The random-view test with K views an example (docs/techniques.md, "From every side"): every
# example x technique against the reference from seeded cameras; writes $(BUILD)/views-report.md
# and the failing views' images to $(BUILD)/views-images. `make test` runs it with 2 views.
K ?= 200
test-views: build
	cd $(BUILD) && ./test_views --views $(K) --size 64 --report views-report.md --images views-images

# meso sweep on a real one-node Slurm cluster started for the test (docs/scale-out.md): a job
# array of 3 shards and a dependent merge against a single process, a shard cancelled and
# submitted again. Skipped, with a message, where the cluster cannot start.
test-slurm: build
	bash scripts/test-slurm.sh $(BUILD)/meso

# The whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer (CI runs it).
test-asan: deps
	cmake -S . -B $(BUILD_ASAN) -DCMAKE_BUILD_TYPE=Debug -DMESO_SANITIZE=ON -DMESO_NATIVE=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD_ASAN) -j $(JOBS)
	cd $(BUILD_ASAN) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
		LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
		ctest --output-on-failure -j $(JOBS)

# The whole suite built by clang with UndefinedBehaviorSanitizer and float-cast-overflow (CI
# runs it; docs/robustness.md): out-of-range float-to-int conversions GCC cannot report. It
# also builds libmeso.so (-DMESO_SHARED=ON), so CI's install test covers the shared library.
test-clang: deps
	cmake -S . -B $(BUILD_CLANG) -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo \
		-DMESO_SANITIZE_FLOAT=ON -DMESO_NATIVE=OFF -DMESO_SHARED=ON $(CMAKE_FLAGS)
	cmake --build $(BUILD_CLANG) -j $(JOBS)
	cd $(BUILD_CLANG) && UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j $(JOBS)

bench: build
	$(BUILD)/meso bench

# make install PREFIX=/opt/meso (default: the build's CMAKE_INSTALL_PREFIX, /usr/local)
install: build
	cmake --install $(BUILD) $(if $(PREFIX),--prefix $(PREFIX))

# Every relative link and #anchor of README.md, CONTRIBUTING.md and docs/ resolves (ctest runs it
# too, as docs_check).
docs-check:
	/usr/bin/python3 scripts/docs-check.py

format:
	clang-format -i $$(git ls-files '*.c' '*.h')

# CI: the tree as .clang-format has it (Debian's clang-format 14).
format-check: deps
	clang-format --dry-run --Werror $$(git ls-files '*.c' '*.h')

clean:
	rm -rf $(BUILD) $(BUILD_ASAN) $(BUILD_CLANG)
