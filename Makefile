# Entry points; the README starts with `make all` and `make test`.
SHELL := /bin/bash
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-from-lock
UV_VERSION := 0.13.8
# uv gives up compiling a file after 60 s, which a heavily loaded 2-core machine can exceed
export UV_COMPILE_BYTECODE_TIMEOUT ?= 600
CORES ?= 2
# any Python >= 3.11 with venv, e.g. PYTHON=/usr/bin/python3 (a PEP 668 system interpreter is fine:
# nothing is installed into it)
PYTHON ?= python3
# an installed uv is used as it is; without one, uv $(UV_VERSION) goes to .tools/bin/uv. It is
# installed into a temporary venv and renamed into place, so an interrupted install (Ctrl-C)
# never leaves a half-written .tools/bin/uv; one that does not answer --version is replaced.
UV ?= $(shell command -v uv 2>/dev/null)
FIND_UV = uv="$(UV)"; if [ -z "$$uv" ]; then uv=.tools/bin/uv; \
	if ! "$$uv" --version >/dev/null 2>&1; then \
	mkdir -p .tools/bin && tmp="$$(mktemp -d .tools/install.XXXXXX)" && trap 'rm -rf "$$tmp"' EXIT && \
	"$(PYTHON)" -m venv "$$tmp/venv" && "$$tmp/venv/bin/pip" install --quiet uv==$(UV_VERSION) && \
	"$$tmp/venv/bin/uv" --version >/dev/null && mv -f "$$tmp/venv/bin/uv" .tools/bin/uv || exit 1; \
	fi; fi

.PHONY: setup setup-peers all check test lock lint dag bench report clean-corrupt clean-results

## setup: create .venv with uv from the hash-pinned environment.lock and install the package (editable)
setup: $(STAMP)

# The stamp goes first and comes back last: a set-up interrupted anywhere leaves none, and the
# next one starts from a clean venv (--clear) instead of trusting a half-synced one.
$(STAMP): environment.lock pyproject.toml
	@$(FIND_UV); \
	if [ -e $@ ] && $(BIN)/python -c "" 2>/dev/null; then keep=--allow-existing; else keep=--clear; fi; \
	rm -f $@; set -x; \
	$$uv venv $$keep --python "$(PYTHON)" $(VENV) && \
	$$uv pip sync --python $(BIN)/python --require-hashes --compile-bytecode environment.lock && \
	$$uv pip install --python $(BIN)/python --no-deps --compile-bytecode -e . && \
	touch $@

## setup-peers: Debian's PETSc with petsc4py for /usr/bin/python3 (as root), the work-precision study's PETSc peers
setup-peers:
	apt-get install -y --no-install-recommends python3-petsc4py-real
	/usr/bin/python3 workflow/peers/petsc_peer.py probe

## all: set up, then run the whole pipeline (paper scene -> paper_figures/)
all: setup
	$(BIN)/snakemake -c$(CORES) all

## check: compare paper_figures/ of your run with the committed files (git HEAD): per file identical, or how far its numbers differ
check: setup
	$(BIN)/python -m signorini.pipeline.check

## test: set up, then run the test suite on $(CORES) workers, a test file per worker (what .ci/run calls)
test: setup
	$(BIN)/pytest -q -n $(CORES) --dist loadfile --no-loadscope-reorder --durations=15

## lock: recompile environment.lock from requirements.in (pinned, with hashes)
lock:
	@$(FIND_UV); $$uv pip compile --python-version 3.11 --generate-hashes requirements.in -o environment.lock

## lint: ruff, snakemake --lint, snakefmt --check
lint: setup
	$(BIN)/ruff check src tests workflow benchmarks notebooks
	$(BIN)/snakemake --lint
	$(BIN)/snakefmt --check Snakefile workflow

## dag: redraw the rule graph shown in the README (needs graphviz's dot)
dag: setup
	$(BIN)/snakemake --rulegraph dot all | dot -Tpng -Gdpi=100 -o workflow/rulegraph.png

## report: the Snakemake report of every result that exists (built here or committed): results/report.html
report: setup
	@$(BIN)/python -m signorini.studies.report build

## bench: wall time of a cold `snakemake -c2 all`, a no-op rerun and a dry run (medians of 5) -> results/benchmarks/bench.json
bench: setup
	$(BIN)/python benchmarks/workflow.py

## clean-corrupt: delete what runs moved aside, damaged or out of date (results/**/*.corrupt, *.stale; results/ may be a link)
clean-corrupt:
	@if [ -e results ]; then find -L results \( -name '*.corrupt' -o -name '*.stale' \) -type f -print -delete; \
	else echo "clean-corrupt: no results/ here: nothing to delete"; fi

## clean-results: remove the cache (results/) and Snakemake's metadata
clean-results:
	rm -rf results .snakemake
