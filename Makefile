# Every target sets itself up: a fresh machine needs only `make demo` or `make test`.
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
APT_PACKAGES := libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6
export MUJOCO_GL ?= egl

.PHONY: setup demo test test-all bench bench-returns lint format docs perception-model clean

setup: $(STAMP)

$(STAMP): pyproject.toml Makefile
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing apt packages for offscreen rendering:$$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi
	@[ -x $(PY) ] || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q "torch==2.13.0"
	$(PY) -m pip install -q -e ".[dev,ray]"
	@touch $(STAMP)

demo: setup
	$(VENV)/bin/strug demo

test: setup
	$(PY) -m pytest -q

test-all: setup
	$(PY) -m pytest -q -m "slow or not slow"

bench: setup
	$(PY) -m pip install -q "pomdp-py==1.3.5.1"
	$(PY) tools/bench_tree_search.py

bench-returns: setup
	$(PY) -m pip install -q "pomdp-py==1.3.5.1"
	$(PY) tools/bench_returns.py

lint: setup
	$(VENV)/bin/ruff check . && $(VENV)/bin/ruff format --check .

format: setup
	$(VENV)/bin/ruff format . && $(VENV)/bin/ruff check --fix .

docs: setup
	$(PY) -m pip install -q -e ".[docs]"
	$(VENV)/bin/mkdocs build --strict

# Retrain the perception network from scratch (about 55 min on 2 cores): render the
# training and tuning views (resumable), train (resumable: add RESUME=--resume), write
# models/perception/ (weights, metrics, training curve). models/perception/README.md.
perception-model: setup
	$(PY) tools/render_perception_data.py --seeds 100000:100600 --out data/perception/train \
	    --empty-prob 0.05 --furniture 0.5
	$(PY) tools/render_perception_data.py --seeds 3000:3030 --out data/perception/tune
	$(PY) tools/train_perception.py --train data/perception/train --test data/perception/tune \
	    --epochs 12 $(RESUME)

clean:
	rm -rf $(VENV) .pytest_cache build *.egg-info
