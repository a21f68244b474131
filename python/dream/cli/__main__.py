"""``python -m dream.cli``: the same command line as the ``dream`` script."""

from dream.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
