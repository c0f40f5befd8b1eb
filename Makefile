# Two commands do all the set-up: `make run` and `make test` (each creates .venv if missing).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= out

.PHONY: run test lint bench clean

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

$(VENV)/.installed: pyproject.toml $(BIN)/activate
	$(BIN)/pip install --quiet -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml $(VENV)/.installed
	$(BIN)/pip install --quiet -e '.[test]'
	touch $@

run: $(VENV)/.installed
	$(BIN)/nnrobust run paper-ellipse --controller nn --out $(OUT)/paper-ellipse-nn --overwrite
	$(BIN)/nnrobust run paper-ellipse --controller no-u0 --out $(OUT)/paper-ellipse-no-u0 --overwrite
	$(BIN)/nnrobust compare $(OUT)/paper-ellipse-nn $(OUT)/paper-ellipse-no-u0 --out $(OUT)/paper-ellipse-compare

test: $(VENV)/.installed-test
	$(BIN)/ruff check nnrobust tests benchmarks
	$(BIN)/python -m pytest -q

bench: $(VENV)/.installed
	$(BIN)/python benchmarks/model_evaluation.py --json $(OUT)/bench/model_evaluation.json
	$(BIN)/python benchmarks/closed_loop.py --json $(OUT)/bench/closed_loop.json

clean:
	rm -rf $(VENV) $(OUT) *.egg-info
