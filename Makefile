# Two commands on a fresh machine:  make demo   (set up, run the main job on quet_paris)
#                                   make test   (set up, run every test)
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed-stamp

.PHONY: demo test setup bench clean

$(STAMP): setup.py package.xml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

demo: $(STAMP)
	mkdir -p out
	tools/loopback $(VENV)/bin/gyro-instrument describe quet_paris
	AMENT_PREFIX_PATH=$(abspath $(VENV)) tools/loopback $(VENV)/bin/gyro-instrument run quet_paris --bag out/quet_paris.mcap --overwrite

test: $(STAMP)
	AMENT_PREFIX_PATH=$(abspath $(VENV)) tools/loopback $(PY) -m pytest -ra --durations=25

clean:
	rm -rf $(VENV) build install log out .pytest_cache
