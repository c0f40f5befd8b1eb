# Two commands do all the set-up: `make run` and `make test` (each creates .venv if missing).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
OUT ?= out

.PHONY: run test lint bench bench-check docs-data mutations clean FORCE

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

# The build requirements of pyproject.toml, installed into the venv once, so that the editable
# install builds without isolation: stable paths keep the build in build/ incremental (a C++ edit
# recompiles only that file). Without a C++ compiler the package installs without the compiled
# loop (docs/compiled.md).
$(VENV)/.build-deps: pyproject.toml $(BIN)/activate
	$(BIN)/python -c "import tomllib; print(*tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires'])" \
	  | xargs $(BIN)/pip install --quiet
	touch $@

# Every C++ file under csrc/ (any depth): an edit anywhere rebuilds the extension.
SOURCES := CMakeLists.txt $(shell find csrc -name '*.hpp' -o -name '*.h' -o -name '*.cpp')

# The editable install knows the package's modules by the list it saw when it was made: a module
# added, moved or removed since needs a reinstall (seconds; nothing recompiles). This stamp changes
# only when that list does.
MODULES := $(sort $(shell find nnrobust -name '*.py'))
$(VENV)/.modules: FORCE | $(BIN)/activate
	@echo "$(MODULES)" | cmp -s - $@ || echo "$(MODULES)" > $@

# The package with pyproject.toml's `walkthrough` extra (sweep, tune, falsify, study, MuJoCo,
# learning), so that after `make run` every command README.md shows works.
$(VENV)/.installed: pyproject.toml $(SOURCES) $(VENV)/.build-deps $(VENV)/.modules
	CMAKE_BUILD_PARALLEL_LEVEL=2 $(BIN)/pip install --quiet --no-build-isolation -e '.[walkthrough]'
	touch $@

# The suite also tests the rl extra (PPO and SAC: Stable-Baselines3 on PyTorch): PyTorch's CPU
# build first (TORCH; about 30 s and 850 MB here), so that the extra's `torch>=2.3` finds it
# installed and no CUDA build (several GB) is fetched. Elsewhere,
# TORCH='torch --index-url https://download.pytorch.org/whl/cpu' does the same. The test extra
# alone leaves PyTorch out (its RL tests then skip, saying so).
TORCH ?= torch==2.13.0
$(VENV)/.installed-test: pyproject.toml $(VENV)/.installed
	$(BIN)/pip install --quiet $(TORCH)
	CMAKE_BUILD_PARALLEL_LEVEL=2 $(BIN)/pip install --quiet --no-build-isolation -e '.[test,rl]'
	touch $@

run: $(VENV)/.installed
	$(BIN)/nnrobust run paper-ellipse --controller nn --out $(OUT)/paper-ellipse-nn --overwrite
	$(BIN)/nnrobust run paper-ellipse --controller no-u0 --out $(OUT)/paper-ellipse-no-u0 --overwrite
	$(BIN)/nnrobust compare $(OUT)/paper-ellipse-nn $(OUT)/paper-ellipse-no-u0 --out $(OUT)/paper-ellipse-compare

# The browser test renders animation.html in headless Chromium. Install Debian's chromium when it
# is missing and we can (root with apt-get); elsewhere that test skips and says why.
$(VENV)/.browser: $(BIN)/activate
	@if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1; then \
	  echo "chromium: $$(command -v chromium || command -v chromium-browser)"; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  (DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null 2>&1 || \
	   (apt-get update -q >/dev/null 2>&1 && DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null 2>&1)) \
	  && echo "chromium installed" || echo "chromium could not be installed: the browser test will skip"; \
	else \
	  echo "chromium missing and apt-get unavailable (not root): the browser test will skip"; \
	fi
	touch $@

# Where a C++ compiler is, the compiled loop must have been built: its tests fail instead of skipping.
# The suite runs on one pytest-xdist process per logical CPU (10 min instead of 16 on 2 cores).
REQUIRE_COMPILED := $(if $(shell command -v c++ 2>/dev/null),1,0)

test: $(VENV)/.installed-test $(VENV)/.browser
	$(BIN)/ruff check nnrobust tests benchmarks docs examples
	$(BIN)/ruff format --check nnrobust tests benchmarks docs examples
	$(BIN)/mypy
	NNROBUST_REQUIRE_COMPILED=$(REQUIRE_COMPILED) $(BIN)/python -m pytest -q -n logical

bench: $(VENV)/.installed
	$(BIN)/nnrobust bench --out $(OUT)/bench

# The compiled loop's speed goals (benchmarks/bench_check.py): about a minute, on a quiet machine;
# fails, naming the part of the step that grew, when a goal is missed.
bench-check: $(VENV)/.installed
	$(BIN)/python benchmarks/closed_loop.py --json $(OUT)/bench/closed_loop.json
	$(BIN)/python benchmarks/loop_profile.py --json $(OUT)/bench/loop_profile.json
	$(BIN)/python benchmarks/bench_check.py $(OUT)/bench/closed_loop.json $(OUT)/bench/loop_profile.json

# Every number in README.md and docs/: regenerate each data file (about 1.5 hours on 2 cores;
# the resumable tunings and searches start afresh, so a changed plant or tuner is not replayed),
# then rewrite the tables from them (tests/docs_numbers/ checks both).
DATA := docs/data
docs-data: $(VENV)/.installed-test
	$(BIN)/python benchmarks/paper_reproduction.py --json $(DATA)/paper_reproduction.json
	$(BIN)/python benchmarks/friction_compensation.py --json $(DATA)/friction_compensation.json
	$(BIN)/python benchmarks/nn_options.py --json $(DATA)/nn_options.json
	$(BIN)/python benchmarks/subtask.py --json $(DATA)/subtask.json
	$(BIN)/python benchmarks/arm_presets.py --json $(DATA)/arm_presets.json
	$(BIN)/python benchmarks/torque_speed.py --json $(DATA)/torque_speed.json
	rm -rf $(OUT)/tuned-paper $(OUT)/tuned-panda $(OUT)/falsify-paper $(OUT)/falsify-panda $(OUT)/tune-noisy \
	  $(OUT)/falsify-paper-tuned $(OUT)/falsify-panda-tuned $(OUT)/paper-robustness $(OUT)/panda-robustness
	for study in tuned-paper tuned-panda falsify-paper falsify-panda falsify-paper-tuned falsify-panda-tuned \
	  paper-robustness panda-robustness; do \
	  $(BIN)/nnrobust study benchmarks/studies/$$study.toml --out $(OUT)/$$study --workers 2 --quiet && \
	  sed "s|$(CURDIR)/||g" $(OUT)/$$study/report.json > $(DATA)/$$(echo $$study | tr - _).json || exit 1; \
	done
	rm -rf $(OUT)/study && $(BIN)/nnrobust study examples/study.toml --out $(OUT)/study --workers 2 --quiet
	sed "s|$(CURDIR)/||g" $(OUT)/study/report.json > $(DATA)/example_study.json
	for policy in ppo-residual ppo-torque; do \
	  cp $(OUT)/study/cases/paper-ellipse-noisy/train/$$policy/curves.png docs/img/example_$$(echo $$policy | tr - _)_curves.png || exit 1; \
	done
	$(BIN)/python benchmarks/studies/fronts.py $(OUT)/tuned-paper $(OUT)/tuned-panda --figure docs/img/tuned_comparison.png
	$(BIN)/python benchmarks/engine_gap.py --json $(DATA)/engine_gap.json
	$(BIN)/python benchmarks/worst_plant_loops.py --json $(DATA)/worst_plant_loops.json
	test -d $(OUT)/FrankaEmikaPandaDynModel || git clone --depth 1 \
	  https://github.com/marcocognetti/FrankaEmikaPandaDynModel $(OUT)/FrankaEmikaPandaDynModel
	$(BIN)/python benchmarks/identify_panda.py $(OUT)/FrankaEmikaPandaDynModel --json $(DATA)/identify_panda.json
	$(BIN)/python benchmarks/identify_calibration.py --json $(DATA)/identify_calibration.json
	$(BIN)/python benchmarks/identify_walkthrough.py --json $(DATA)/identify_walkthrough.json
	$(BIN)/python benchmarks/plant_convergence.py --json $(DATA)/plant_convergence.json
	$(BIN)/python benchmarks/adaptive_step.py --json $(DATA)/adaptive_step.json
	$(BIN)/python benchmarks/interval_coverage.py --json $(DATA)/interval_coverage.json --figure docs/img/interval_coverage.png
	$(BIN)/nnrobust tune paper-ellipse-noisy --controllers nn,no-u0,pd,sliding-mode,slotine-li,rbf-nn --budget 120 \
	  --max-rms-torque 10 --max-saturated 0.01 --workers 2 --out $(OUT)/tune-noisy --overwrite --quiet
	cp $(OUT)/tune-noisy/summary.json $(DATA)/tune_noisy_case_b.json
	$(BIN)/python docs/render_tables.py

# The test suite must catch each of benchmarks/mutations.py's broken lines (about 4 minutes).
mutations: $(VENV)/.installed-test
	$(BIN)/python benchmarks/mutations.py

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info
