# contactbench — the two commands a user needs are `make demo` and `make test`.
SHELL := /bin/bash
BUILD ?= build
JOBS ?= $(shell nproc)
PY := /usr/bin/python3
CB := $(BUILD)/bin/contactbench
CB_CACHE ?= $(HOME)/.cache/contactbench
# The authors' data (meshes, scenes, figure tables), written by `make paper-data`.
DATA ?= $(CB_CACHE)/paper-data
# Where `make paper-data` fetches the authors' tree from: a git URL, a folder or a .tar.gz.
PAPER_DATA_SOURCE ?= https://github.com/simba518/MPRGP.git
# ccache is looked up when a recipe runs, not when make reads this file: `make deps` may have just
# installed it. CMakeLists.txt sets its base_dir to the source tree (shared objects across checkouts).
CONFIGURE = cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release \
  $$(command -v ccache >/dev/null 2>&1 && echo -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# The perf gate (tools/perf_gate.py): BASE=<rev> overrides the base revision; PERF_GATE_ARGS
# passes more options (e.g. --filter '/mprgp$$' --repeats 3).
GATE = CB_CACHE="$(CB_CACHE)" $(PY) tools/perf_gate.py
export OPENBLAS_NUM_THREADS ?= 1
export MPLBACKEND ?= Agg

DEB_PACKAGES := build-essential cmake git zlib1g-dev libeigen3-dev libsuitesparse-dev nlohmann-json3-dev \
  libgtest-dev libbenchmark-dev libopenblas0-pthread \
  python3-numpy python3-pandas python3-matplotlib python3-scipy python3-pyflakes clang-format libcgal-demo \
  ccache valgrind libjs-d3 chromium chromium-driver python3-selenium \
  pkg-config coinor-libipopt-dev libsiconos-numerics-dev libfclib-dev libbullet-dev
# PEERS=all: also PETSc (about 180 MB) for the TAO peers (docs/peers.md); not in the default set.
ifeq ($(PEERS),all)
DEB_PACKAGES += petsc-dev
endif

.PHONY: help deps build test demo bench timing baseline reproduce decoupling stress fuzz clean meshes paper-data docs-check tidy lint ladder friction-suite \
  ci-perf perf-gate perf-gate-selftest contactbench-binary

help:
	@echo "make demo       install, build, simulate a small scene, run the solvers, write figures"
	@echo "make test       install, build from scratch (Release), run every C++ and Python test + CI perf gate"
	@echo "make perf-gate  same-machine A/B of the CI suite against BASE (default: the commit of the baseline)"
	@echo "make deps       install the Debian packages (apt-get, as root); quick when present"
	@echo "                (PEERS=all: PETSc too, about 180 MB, for the TAO peers)"
	@echo "make build      configure and build into $(BUILD)/"
	@echo "make bench      Google Benchmark suite (JSON in results/bench/)"
	@echo "make timing     monitored vs unmonitored time of every solver (ratio <= 1.2; also in make test, serially)"
	@echo "make baseline   re-record results/baselines/ci.csv from a clean tree (commit it alone, after the change)"
	@echo "make paper-data fetch the authors' repository (simba518/MPRGP at 57fdd2c), verify it, extract"
	@echo "                meshes, scenes and figure tables into DATA=$(DATA) (PAPER_DATA_SOURCE=URL|DIR|.tar.gz)"
	@echo "make reproduce  the paper's figures and report in results/paper/ (full: most of an hour on 2 cores, QUICK=1: minutes; measured times in README)"
	@echo "make decoupling the price of collision decoupling along chains (results/decoupling/)"
	@echo "make friction-suite the frictional suite: frames, runs at 1e-4 and 1e-8 in rounds, profiles (results/friction/)"
	@echo "make docs-check fail on a cited document, section or path that is not in the repository, or a stale count"
	@echo "make tidy       clang-tidy on the C++ files changed against main (TIDY_BASE=main)"
	@echo "make lint       pyflakes on every Python file, clang-format on C++ lines changed against main (LINT_BASE=main)"
	@echo "make stress     the stress suite and its stability table in results/stress/"
	@echo "make ladder     which solver when: LADDER=resolution (8k-1M DOFs) or density (8-8840 rows), results/ladder/"
	@echo "make fuzz       fuzz the snapshot, suite, scene, solution and FCLIB readers (FUZZ_SECONDS=60 each)"

deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" != 0 ]; then \
	    echo "make deps: missing Debian packages:$$missing"; \
	    echo "run as root: apt-get update && apt-get install -y$$missing"; exit 1; \
	  fi; \
	  echo "make deps: installing$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null || exit 1; \
	else echo "make deps: all Debian packages present"; fi
	@$(MAKE) --no-print-directory meshes

# Surface meshes of the classic models, unpacked from Debian's libcgal-demo into a cache.
meshes:
	@if [ ! -f "$(CB_CACHE)/meshes/bunny00.off" ]; then \
	  mkdir -p "$(CB_CACHE)/meshes" && \
	  tar -xzf /usr/share/doc/libcgal-dev/data.tar.gz -C "$(CB_CACHE)" --wildcards '*/meshes/*.off' \
	    --transform='s,.*/meshes/,meshes/,' && echo "meshes: unpacked CGAL data into $(CB_CACHE)/meshes"; \
	fi

$(BUILD)/CMakeCache.txt:
	$(CONFIGURE)

build: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# Stages (deps, configure, build, ctest, perf gate) each timed, with a table at the end.
test:
	@tools/make_test.sh $(BUILD) $(JOBS)

contactbench-binary: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS) --target contactbench

# CI performance gate: the CI suite run by BASE's binary and this tree's, on this machine,
# interleaved; work counters exact, instructions in the solve (callgrind) within 3%, wall time
# judged beyond 1.5x. Without a buildable BASE it falls back to ci-perf. Exit 3: a regression.
perf-gate: contactbench-binary
	$(GATE) gate --new-binary $(CB) --jobs $(JOBS) $(if $(BASE),--base $(BASE)) $(PERF_GATE_ARGS)

# Against the committed record (results/baselines/ci.csv), with the across-machines rules.
ci-perf: contactbench-binary
	$(GATE) check --new-binary $(CB) --jobs $(JOBS) $(PERF_GATE_ARGS)

# Re-record the compact baseline from a clean tree; commit it alone, right after the change.
baseline: contactbench-binary
	$(GATE) record --binary $(CB) --jobs $(JOBS)

# End to end: a scratch clone with a planted regression through `make perf-gate` (real worktree
# build of BASE; slow: two builds of contactbench).
perf-gate-selftest:
	tests/perf/selftest.sh

demo: deps build
	$(CB) simulate scenes/demo.json --out results/demo/sim --fresh
	$(PY) -m plots.strip results/demo/sim
	$(CB) run suites/demo.json --out results/demo
	$(PY) -m plots.convergence results/demo
	$(PY) -m plots.profiles results/demo
	$(PY) -m plots.html_report results/demo
	$(PY) -m plots.reproduce --contactbench $(CB) --data $(DATA) --out results/paper --quick
	@echo "demo: simulation pictures in results/demo/sim/, solver figures and profiles in results/demo/figures/,"
	@echo "      the paper's figures and claims (quick mode) in results/paper/report.md"
	@echo "      open in a browser (offline): results/demo/report/index.html, results/paper/report/index.html"

# The paths reach the command through the environment, never spliced into the shell line.
paper-data: export CB_CACHE := $(CB_CACHE)
paper-data: export PAPER_DATA_SOURCE := $(PAPER_DATA_SOURCE)
paper-data: export CB_PAPER_DATA_DEST := $(DATA)
paper-data:
	$(PY) -m plots.paper_data --source "$$PAPER_DATA_SOURCE" --dest "$$CB_PAPER_DATA_DEST"

docs-check:
	$(PY) tests/python/docs_check.py .

lint:
	tools/lint.sh $(or $(LINT_BASE),main)

tidy: $(BUILD)/CMakeCache.txt
	tools/tidy-changed.sh $(BUILD) $(or $(TIDY_BASE),main)

# Same-run timing ratios (monitored vs unmonitored runs of every solver), by themselves; `make test`
# runs them too, serially (ctest label `timing`).
timing: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS) --target test_monitor_timing
	OPENBLAS_NUM_THREADS=1 $(BUILD)/tests/test_monitor_timing

bench: build
	mkdir -p results/bench
	$(BUILD)/bin/cb_bench --benchmark_out=results/bench/bench.json --benchmark_out_format=json

reproduce: deps build
	$(PY) -m plots.reproduce --contactbench $(CB) --data $(DATA) --out results/paper $(if $(QUICK),--quick,)

# Which solver when (issue 29): LADDER=resolution (8k to 1M DOFs) or density (8 to 8840 rows at 100k DOFs).
LADDER ?= resolution
ladder: build
	tools/ladder.sh $(LADDER) $(CB)

# The price of decoupling along chains (docs/simulator.md "The price of decoupling"), each scene at
# its step and half of it, cached per scene and step under results/decoupling/chains.
DECOUPLING_SCENES ?= two_dinos_1303 two_dinos_1493 two_dinos_5910 two_dinos_9381 two_dinos_20044 long_cube \
  bunny_glass dragon_stair
decoupling: build
	$(PY) plots/decoupling.py $(foreach s,$(DECOUPLING_SCENES),scenes/$(s).json) --cb $(CB) --out results/decoupling
	$(PY) plots/decoupling.py scenes/dino_eight.json --frames 160 --cb $(CB) --out results/decoupling

# The frictional suite (docs/friction.md "The frictional suite"): the frictional frames and converted
# FCLIB files, suites/friction.json at tol 1e-4 and 1e-8 in interleaved rounds, profiles and claim.
friction-suite: build
	$(PY) plots/friction_suite.py --cb $(CB) --out results/friction

stress: build
	$(CB) stress --out results/stress
	$(PY) -m plots.stability results/stress
	$(PY) -m plots.html_report results/stress

# Each reader on its own corpus: FUZZ_SECONDS per target (FUZZ_TARGETS to pick some).
FUZZ_TARGETS ?= qpsnap suite scene solution fclib
fuzz: deps
	cmake -S . -B $(BUILD)-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCB_FUZZ=ON \
	  -DCB_BUILD_TESTS=OFF -DCB_BUILD_BENCH=OFF
	cmake --build $(BUILD)-fuzz -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	for t in $(FUZZ_TARGETS); do \
	  corpus=tests/fuzz/corpus; [ $$t = qpsnap ] || corpus=tests/fuzz/corpus_$$t; \
	  mkdir -p $(BUILD)-fuzz/corpus_$$t && cp $$corpus/* $(BUILD)-fuzz/corpus_$$t/ && \
	  $(BUILD)-fuzz/bin/fuzz_$$t -max_total_time=$(or $(FUZZ_SECONDS),60) -timeout=10 -rss_limit_mb=2048 \
	    -artifact_prefix=$(BUILD)-fuzz/$$t- $(BUILD)-fuzz/corpus_$$t || exit 1; \
	done

clean:
	rm -rf $(BUILD) $(BUILD)-*
