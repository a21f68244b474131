# DREAM developer tasks. `make help` lists them.
.PHONY: lint help build-dev test test-pure bench stubs wheel docs docs-serve

help:  ## list the targets
	@grep -E '^[a-z-]+:.*##' $(MAKEFILE_LIST) | sed 's/:.*## /\t/'

build-dev:  ## editable install: Python edits are live, rerun after Rust edits
	pip install -e ".[test]"

test:  ## what CI runs: the README's test command, then .ci/package (wheel, sdist, docs)
	bash .ci/run

test-pure:  ## the Python suite on the NumPy reference kernels only
	DREAM_PURE_PYTHON=1 python -m pytest

bench:  ## benchmark figures for docs/benchmarks.md (medians and ratios, one run)
	cd benches && python bench_kernels.py && python bench_experiments.py

stubs:  ## check python/dream/_core.pyi against the compiled module
	python -m mypy.stubtest dream._core

wheel:  ## dist/: the abi3 wheel (any CPython >= 3.10, no Rust needed to install) and the sdist
	maturin build --release --out dist
	maturin sdist --out dist

docs:  ## site/: the documentation, warnings as errors (needs the docs extra: pip install ".[docs]")
	mkdocs build --strict

docs-serve:  ## the documentation on http://127.0.0.1:8000, rebuilt on every edit
	mkdocs serve

lint:  ## format and lint gates of CI: cargo fmt, clippy -D warnings, ruff format, ruff check, mypy
	bash .ci/lint
