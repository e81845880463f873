"""``python -m brdfkit``: the same command line as the ``brdfkit`` console script."""

from .cli import run

if __name__ == "__main__":
    run()
