# make demo : set up (first time only) and run the default scene into out/drop-on-square
# make test : set up (first time only) and run the test suite
# make bench: run the benchmarks (heavy measurements, not part of the tests)
VENV := .venv
PY := $(VENV)/bin/python

.PHONY: setup demo test bench clean
setup:
	@sh scripts/bootstrap.sh

demo: setup
	$(PY) -m clothsim run

test: setup
	$(VENV)/bin/ruff check clothsim tests benchmarks examples scripts
	$(PY) -m pytest -q

bench: setup
	$(PY) -m benchmarks

clean:
	rm -rf out .pytest_cache .hypothesis
