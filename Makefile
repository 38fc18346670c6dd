# Two entry points for a fresh machine with Python 3.11 (see README):
#   make console   set up .venv and start the console on the default scene
#   make test      set up .venv (and Debian's chromium for the browser tests) and run the test suite
PYTHON ?= python3.11
VENV ?= .venv
PY := $(VENV)/bin/python
ARGS ?=
# the browser tests' screenshots go here (git-ignored: out/); a CI run keeps the folder as its artifacts
HRP2_ARTIFACTS ?= out/artifacts

.PHONY: console test setup browser bench

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	$(PY) -c "import mujoco, pinocchio, placo, viser, qpsolvers"
	touch $@

setup: $(VENV)/.installed

browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; fi; }

console: setup
	$(VENV)/bin/hrp2-console $(ARGS)

test: setup browser
	MUJOCO_GL=egl HRP2_ARTIFACTS=$(abspath $(HRP2_ARTIFACTS)) $(PY) -m pytest $(ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing"; exit 1; fi; exit $$rc

bench: setup
	$(VENV)/bin/hrp2-console bench $(ARGS)
