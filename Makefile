# Two entry points for a fresh machine with Python 3.11 (see README):
#   make console   set up .venv and start the console on the default scene
#   make test      set up .venv (and Debian's chromium for the browser tests) and run the test suite
# and, as .ci/run does after `make test`:
#   make test-py313   set up .venv313 on Python 3.13 and run the unit tests and one walk there
PYTHON ?= python3.11
VENV ?= .venv
PY := $(VENV)/bin/python
# requires-python says 3.11-3.13: the newest one too, in an environment of its own (PYTHON313=... if it is
# not on PATH under this name)
PYTHON313 ?= python3.13
VENV313 ?= .venv313
# on 3.13 the unit tests and one short walking scenario (about a minute), not the whole suite
TESTS313 ?= tests/controller tests/robot tests/behaviors tests/test_architecture.py \
	'tests/scenarios/test_walking.py::test_go_pos_lands_the_planned_feet_on_the_goal_and_the_simulated_feet_on_the_plan[forward-left-20]'
ARGS ?=
# the browser tests' screenshots go here (git-ignored: out/); a CI run keeps the folder as its artifacts
HRP2_ARTIFACTS ?= out/artifacts

.PHONY: console test test-py313 setup browser bench

# a virtual environment with the package and its test tools: $(1) the interpreter, $(2) the folder
define install_venv
	$(1) -m venv $(2)
	$(2)/bin/python -m pip install --quiet --upgrade pip
	$(2)/bin/python -m pip install --quiet -e '.[test]'
	$(2)/bin/python -c "import mujoco, pinocchio, placo, viser, qpsolvers"
	touch $(2)/.installed
endef

$(VENV)/.installed: pyproject.toml
	$(call install_venv,$(PYTHON),$(VENV))

$(VENV313)/.installed: pyproject.toml
	@$(PYTHON313) -c 'import sys; sys.exit(sys.version_info[:2] != (3, 13))' || { \
	  echo "$(PYTHON313) is not a Python 3.13 (or is missing): give one with PYTHON313=..." >&2; exit 1; }
	$(call install_venv,$(PYTHON313),$(VENV313))

setup: $(VENV)/.installed

browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; fi; }

console: setup
	$(VENV)/bin/hrp2-console $(ARGS)

# two passes (tests/conftest.py): the in-process tests on two workers, then the rest one at a time; both run,
# either failing fails, and so does selecting no test in both (pytest's 5; ARGS may pick tests of one pass only)
TEST_ENV = MUJOCO_GL=egl HRP2_ARTIFACTS=$(abspath $(HRP2_ARTIFACTS))
test: setup browser
	$(TEST_ENV) HRP2_TEST_PASS=parallel $(PY) -m pytest -n 2 --dist loadfile $(ARGS); rc1=$$?; \
	$(TEST_ENV) HRP2_TEST_PASS=serial $(PY) -m pytest $(ARGS); rc2=$$?; \
	if [ $$rc1 -eq 5 ] && [ $$rc2 -eq 5 ]; then echo "pytest collected no tests: failing"; exit 1; fi; \
	for rc in $$rc1 $$rc2; do if [ $$rc -ne 0 ] && [ $$rc -ne 5 ]; then exit $$rc; fi; done

# pytest's exit code 5 (no test collected: a renamed test) fails here too
test-py313: $(VENV313)/.installed
	MUJOCO_GL=egl $(VENV313)/bin/python -m pytest -m "not slow and not browser" $(TESTS313) $(ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing"; exit 1; fi; exit $$rc

bench: setup
	$(VENV)/bin/hrp2-console bench $(ARGS)
