# The two commands of README.md: `make demo` (the main job) and `make test` (the suite);
# `make fuzz`: the fuzz suite's long campaign (docs/reliability.md, "Fuzzing").
# Each creates the virtual environment from this project's own files when it is missing or stale.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUT    ?= out

# The campaign of `make fuzz`: every fuzz test's examples times FUZZ_EXAMPLES (25: over 5,000
# cases), each case stopped as a hang after FUZZ_TIMEOUT_S seconds; the outcomes in FUZZ_TALLY.
FUZZ_EXAMPLES  ?= 25
FUZZ_TIMEOUT_S ?= 60
FUZZ_TALLY     ?= $(OUT)/fuzz-tally.jsonl

.PHONY: demo test lint bench clean venv fuzz

venv: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $@

demo: venv
	$(BIN)/python -m imucalib.demo --out $(OUT)

test: venv
	$(BIN)/python -m ruff check src tests bench examples
	$(BIN)/python -m mypy
	$(BIN)/python -m pytest -n 2 -q

fuzz: venv
	mkdir -p $(dir $(FUZZ_TALLY))
	rm -f $(FUZZ_TALLY)
	status=0; IMUCALIB_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) IMUCALIB_FUZZ_TIMEOUT_S=$(FUZZ_TIMEOUT_S) IMUCALIB_FUZZ_TALLY=$(abspath $(FUZZ_TALLY)) $(BIN)/python -m pytest -n 2 -q tests/fuzz || status=$$?; $(BIN)/python tests/fuzz/tally.py $(FUZZ_TALLY); exit $$status

lint: venv
	$(BIN)/python -m ruff check src tests bench examples
	$(BIN)/python -m ruff format --check src tests bench || true
	$(BIN)/python -m mypy

bench: venv
	$(BIN)/python bench/bench_twin.py
	$(BIN)/python bench/bench_noise.py
	$(BIN)/python bench/bench_recording.py
	$(BIN)/python bench/bench_allan.py
	$(BIN)/python bench/bench_processing_estimation.py
	$(BIN)/python bench/bench_drivers.py
	$(BIN)/python bench/bench_p1.py
	$(BIN)/python bench/bench_p2.py
	$(BIN)/python bench/bench_analysis.py
	$(BIN)/python bench/bench_import.py
	$(BIN)/python bench/bench_cli_startup.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .mypy_cache .ruff_cache
