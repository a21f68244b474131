# DREAM developer tasks. `make help` lists them.
.PHONY: help build-dev test test-pure bench stubs

help:  ## list the targets
	@grep -E '^[a-z-]+:.*##' $(MAKEFILE_LIST) | sed 's/:.*## /\t/'

build-dev:  ## editable install: Python edits are live, rerun after Rust edits
	pip install -e ".[test]"

test:  ## the README's test command (what CI runs)
	bash .ci/run

test-pure:  ## the Python suite on the NumPy reference kernels only
	DREAM_PURE_PYTHON=1 python -m pytest

bench:  ## benchmark figures for the README (medians and ratios, one run)
	cd benches && python bench_kernels.py && python bench_experiments.py

stubs:  ## check python/dream/_core.pyi against the compiled module
	python -m mypy.stubtest dream._core
