# make demo : set up (first time only) and run the default scene into out/drop-on-square
# make test : set up (first time only) and run the test suite, less the tests marked slow, on
#             every core, each test file whole on one worker, the longest files first
#             (tests/conftest.py LONGEST_FIRST)
#             (.venv/bin/python -m pytest -q -m slow runs those; CI runs both)
# make bench: run the benchmarks (heavy measurements, not part of the tests)
# make docs : build the documentation site into docs/_build/html (runs every gallery lesson;
#             warnings are errors)
VENV := .venv
PY := $(VENV)/bin/python

.PHONY: setup demo test bench docs clean
setup:
	@sh scripts/bootstrap.sh

demo: setup
	$(PY) -m clothsim run

test: setup
	$(VENV)/bin/ruff check clothsim tests benchmarks examples scripts
	$(PY) -m pytest -q -m "not slow" -n auto --dist loadfile --no-loadscope-reorder

bench: setup
	$(PY) -m benchmarks

docs: setup
	MPLBACKEND=Agg $(PY) -m sphinx -W --keep-going -b html docs docs/_build/html

clean:
	rm -rf out .pytest_cache .hypothesis docs/_build docs/auto_examples \
		docs/sg_execution_times.rst
