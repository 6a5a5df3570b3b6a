# Two commands on a fresh machine:  make demo   (set up, run the main job on quet_paris)
#                                   make test   (set up, run every test)
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed-stamp

.PHONY: demo test test-kernels setup bench clean

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
	AMENT_PREFIX_PATH=$(abspath $(VENV)) tools/loopback $(PY) -m pytest -ra --durations=25 -n 2 --dist loadfile

# the tests against shipped files under both OpenBLAS kernel choices of x86-64 machines of this kind
# (AVX-512 where the CPU has it, Haswell's otherwise): their tolerances must hold on either
test-kernels: $(STAMP)
	env -u OPENBLAS_CORETYPE AMENT_PREFIX_PATH=$(abspath $(VENV)) tools/loopback $(PY) -m pytest -q tests/test_bags.py
	OPENBLAS_CORETYPE=Haswell AMENT_PREFIX_PATH=$(abspath $(VENV)) tools/loopback $(PY) -m pytest -q tests/test_bags.py

clean:
	rm -rf $(VENV) build install log out .pytest_cache
