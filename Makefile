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
export OPENBLAS_NUM_THREADS ?= 1
export MPLBACKEND ?= Agg

DEB_PACKAGES := build-essential cmake git zlib1g-dev libeigen3-dev libsuitesparse-dev nlohmann-json3-dev \
  libgtest-dev libbenchmark-dev libopenblas0-pthread \
  python3-numpy python3-pandas python3-matplotlib python3-scipy libcgal-demo

.PHONY: help deps build test demo bench baseline reproduce stress fuzz clean meshes paper-data docs-check tidy

help:
	@echo "make demo       install, build, simulate a small scene, run the solvers, write figures"
	@echo "make test       install, build from scratch (Release), run every C++ and Python test + CI perf gate"
	@echo "make deps       install the Debian packages (apt-get, as root); quick when present"
	@echo "make build      configure and build into $(BUILD)/"
	@echo "make bench      Google Benchmark suite (JSON in results/bench/)"
	@echo "make baseline   rewrite results/baselines/ci from the CI suite (after an intended change)"
	@echo "make paper-data fetch the authors' repository (simba518/MPRGP at 57fdd2c), verify it, extract"
	@echo "                meshes, scenes and figure tables into DATA=$(DATA) (PAPER_DATA_SOURCE=URL|DIR|.tar.gz)"
	@echo "make reproduce  the paper's figures and report in results/paper/ (QUICK=1: about a minute on 2 cores)"
	@echo "make docs-check fail on a cited document or section that is not in the repository"
	@echo "make tidy       clang-tidy on the C++ files changed against main (BASE=main)"
	@echo "make stress     the stress suite and its stability table in results/stress/"
	@echo "make fuzz       fuzz the snapshot reader (FUZZ_SECONDS=60)"

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
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

test: deps
	rm -rf $(BUILD)
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j $(JOBS)
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 600
	@if [ -f suites/ci.json ]; then $(MAKE) --no-print-directory ci-perf; fi

# CI performance gate: the fixed CI suite against the committed baseline (counters exact).
ci-perf:
	rm -rf results/ci-new
	$(CB) run suites/ci.json --out results/ci-new
	$(CB) compare results/baselines/ci results/ci-new

baseline: build
	rm -rf results/baselines/ci.tmp
	$(CB) run suites/ci.json --out results/baselines/ci.tmp
	rm -rf results/baselines/ci && mv results/baselines/ci.tmp results/baselines/ci
	@echo "baseline: rewrote results/baselines/ci (commit it with the change that explains it)"

demo: deps build
	$(CB) simulate scenes/demo.json --out results/demo/sim
	$(CB) run suites/demo.json --out results/demo
	$(PY) -m plots.convergence results/demo
	$(PY) -m plots.profiles results/demo
	$(PY) -m plots.reproduce --contactbench $(CB) --data $(DATA) --out results/paper --quick
	@echo "demo: simulation pictures in results/demo/sim/, solver figures and profiles in results/demo/figures/,"
	@echo "      the paper's figures and claims (quick mode) in results/paper/report.md"

paper-data:
	CB_CACHE="$(CB_CACHE)" $(PY) -m plots.paper_data --source "$(PAPER_DATA_SOURCE)" --dest "$(DATA)"

docs-check:
	$(PY) tests/python/docs_check.py .

tidy: $(BUILD)/CMakeCache.txt
	tools/tidy-changed.sh $(BUILD) $(or $(BASE),main)

bench: build
	mkdir -p results/bench
	$(BUILD)/bin/cb_bench --benchmark_out=results/bench/bench.json --benchmark_out_format=json

reproduce: deps build
	$(PY) -m plots.reproduce --contactbench $(CB) --data $(DATA) --out results/paper $(if $(QUICK),--quick,)

stress: build
	$(CB) stress --out results/stress
	$(PY) -m plots.stability results/stress

fuzz: deps
	cmake -S . -B $(BUILD)-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCB_FUZZ=ON \
	  -DCB_BUILD_TESTS=OFF -DCB_BUILD_BENCH=OFF
	cmake --build $(BUILD)-fuzz -j $(JOBS) --target fuzz_qpsnap
	mkdir -p $(BUILD)-fuzz/corpus && cp tests/fuzz/corpus/* $(BUILD)-fuzz/corpus/
	$(BUILD)-fuzz/bin/fuzz_qpsnap -max_total_time=$(or $(FUZZ_SECONDS),60) -timeout=10 -rss_limit_mb=2048 \
	  -artifact_prefix=$(BUILD)-fuzz/ $(BUILD)-fuzz/corpus

clean:
	rm -rf $(BUILD) $(BUILD)-*
