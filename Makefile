# hh2iec — every target sets itself up: a local venv with every dependency from the package registry.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
SAMPLE := samples/basic_program
OUT := out/basic_program

.PHONY: all venv shim test test-install test-matiec test-beremiz test-openplc demo bench fuzz mutants difftest shards clean

all: test

# pip's own output goes to .venv/install.log, shown only when the install fails.
$(STAMP): pyproject.toml
	@echo "setting up $(VENV): every dependency from the package registry (first run, or pyproject.toml changed)"
	@$(PYTHON) -m venv $(VENV)
	@$(PY) -m pip install --quiet --upgrade pip >$(VENV)/install.log 2>&1 || { cat $(VENV)/install.log; exit 1; }
	@$(PY) -m pip install --quiet -e '.[test]' >>$(VENV)/install.log 2>&1 || { cat $(VENV)/install.log; exit 1; }
	@touch $(STAMP)

venv: $(STAMP)

# The runtime shim library, built once into the per-user cache (as the installed tool does on first use), so that
# parallel test processes find it ready. runtime_shim/Makefile builds the C unit tests.
shim: venv
	$(PY) -c 'from transpiler.exec.compiled.shim import ensure_built; print("runtime shim:", ensure_built())'

test: venv shim
	$(MAKE) -C runtime_shim test
	$(VENV)/bin/hh2iec fetch-schema
	HH2IEC_REQUIRE_SCHEMA=1 HH2IEC_SKIP_ALLOWANCE_FILE=tests/skip_allowance.txt $(PY) -m pytest -q

# The wheel built from this checkout, installed into a new venv in a temporary folder, transpiles and proves the
# sample from outside the checkout (part of `make test` too).
test-install: venv
	$(PY) -m pytest -q tests/test_install.py

# Quiet: the translation's one-line summary and equiv's verdict, coverage and reports, among them the HTML proof
# out/basic_program/proof/index.html (equiv -v: a line per run).
demo: venv
	@$(PY) -c 'from transpiler.exec.compiled.shim import ensure_built; ensure_built()'
	@-$(VENV)/bin/hh2iec fetch-schema >/dev/null || echo "demo: the PLCopen schema could not be fetched; project.xml is not validated" >&2
	@$(VENV)/bin/hh2iec transpile $(SAMPLE)/Main_PGM.src --out $(OUT)
	@$(VENV)/bin/hh2iec equiv $(SAMPLE)/Main_PGM.src $(foreach s,$(wildcard $(SAMPLE)/scenarios/*.yaml),--scenario $(s)) \
		--random-cycles 2000 --seed 1 --report $(OUT)/equiv.json --junit $(OUT)/equiv.junit.xml --html $(OUT)/proof

bench: venv shim
	$(PY) -m tests.bench

fuzz: venv
	$(PY) -m tests.fuzz --mutations 10000

# Mutation self-check of the co-simulation (issue 7): prints the detection rate and the survivors of a seeded
# sample of the sample's mutants; make mutants MUTANTS="--all --constructs" judges every mutant of the sample
# and of each construct project with a scenario (each run must reach 97%).
MUTANTS ?=
mutants: venv shim
	$(PY) -m tests.mutants $(MUTANTS)

# Random-program differential testing (issue 8): make difftest N=10000 SEED=1; SHARD=K/M checks only shard K of M
# of the programs (one CI job each)
N ?= 200
SEED ?= 1
SHARD ?=
difftest: venv shim
	$(PY) -m tests.difftest.run --count $(N) --seed $(SEED) --reduce $(if $(SHARD),--shard $(SHARD))

# The CI sharding recipe of docs/ci.md as local processes (issue 32): the plan once, N shards of equiv on the sample at
# the same time, then hh2iec merge; exits with the merge's status. make shards N=4 (N defaults to 4 here; the N of
# difftest above is a program count). SHARDS_ARGS="--command mutate -- ARGS..." runs another check; --compare also
# runs it unsharded and compares the reports.
SHARDS_N = $(if $(filter command line,$(origin N)),$(N),4)
SHARDS_ARGS ?=
shards: venv shim
	$(PY) -m tests.shards --shards $(SHARDS_N) --out out/shards $(SHARDS_ARGS)

clean:
	rm -rf out build runtime_shim/build .pytest_cache

# matiec's own verdicts (needs MATIEC_HOME: the folder holding iec2c and its lib/). Runs every test file that
# uses iec2c; a skip for lack of iec2c fails the target.
# every test file that looks for iec2c, itself or through the text-project helper
MATIEC_TESTS = $(shell grep -rlE 'find_iec2c|tests.text_project' tests --include='test_*.py' | sort)
test-matiec: venv shim
	@test -x "$(MATIEC_HOME)/iec2c" || { echo "test-matiec: MATIEC_HOME must name the folder holding iec2c and its lib/ (\$$MATIEC_HOME/iec2c not found: '$(MATIEC_HOME)/iec2c')" >&2; exit 1; }
	@log=$$(mktemp); MATIEC_HOME="$(MATIEC_HOME)" $(PY) -m pytest -q -rs $(MATIEC_TESTS) >$$log 2>&1; rc=$$?; cat $$log; \
	if grep -qi "SKIPPED.*iec2c" $$log; then echo "test-matiec: some tests skipped for lack of iec2c" >&2; rc=1; fi; \
	rm -f $$log; exit $$rc

# Beremiz's PLCopen importer on the transpiled projects (docs/import.md): opens project.xml, generates its ST and
# compiles that with iec2c. Needs BEREMIZ_HOME (a Beremiz checkout; nothing of it is built or kept here),
# MATIEC_HOME (iec2c and its lib/) and BEREMIZ_PYTHON (a python with lxml, numpy, matplotlib, zeroconf; default: the
# venv's). A skip fails the target.
test-beremiz: venv
	@test -f "$(BEREMIZ_HOME)/PLCControler.py" || { echo "test-beremiz: BEREMIZ_HOME must name a Beremiz checkout ('$(BEREMIZ_HOME)/PLCControler.py' not found)" >&2; exit 1; }
	@test -x "$(MATIEC_HOME)/iec2c" || { echo "test-beremiz: MATIEC_HOME must name the folder holding iec2c and its lib/ ('$(MATIEC_HOME)/iec2c' not found)" >&2; exit 1; }
	@log=$$(mktemp); BEREMIZ_HOME="$(BEREMIZ_HOME)" MATIEC_HOME="$(MATIEC_HOME)" BEREMIZ_PYTHON="$(BEREMIZ_PYTHON)" \
	$(PY) -m pytest -q -rs tests/test_beremiz_import.py >$$log 2>&1; rc=$$?; cat $$log; \
	if grep -q "SKIPPED" $$log; then echo "test-beremiz: the Beremiz import test skipped" >&2; rc=1; fi; \
	rm -f $$log; exit $$rc

# The OpenPLC v3 runtime's own program build and run on the translated samples (docs/import.md): every sample project
# built with the runtime's steps (its iec2c, g++ of Config0.c/Res0.c, glue generator, link), started, and its coils
# read over Modbus TCP on 127.0.0.1 compared with the reference; the recorded verdicts of tests/data/openplc_verdicts
# measured again. Needs OPENPLC_HOME: an OpenPLC_v3 checkout with utils/matiec_src, utils/libmodbus_src and
# utils/snap7_src built in place (nothing of it is kept here). A skip fails the target.
test-openplc: venv
	@test -x "$(OPENPLC_HOME)/utils/matiec_src/iec2c" || { echo "test-openplc: OPENPLC_HOME must name an OpenPLC_v3 checkout whose utils/matiec_src is built ('$(OPENPLC_HOME)/utils/matiec_src/iec2c' not found)" >&2; exit 1; }
	@log=$$(mktemp); OPENPLC_HOME="$(OPENPLC_HOME)" $(PY) -m pytest -q -rs tests/test_openplc_runtime.py >$$log 2>&1; rc=$$?; cat $$log; \
	if grep -q "SKIPPED" $$log; then echo "test-openplc: some OpenPLC tests skipped" >&2; rc=1; fi; \
	rm -f $$log; exit $$rc
