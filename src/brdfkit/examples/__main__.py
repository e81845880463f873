"""``python -m brdfkit.examples [NAME]``: print the example files' paths (or NAME's)."""

from __future__ import annotations

import sys

from . import FILES, path


def main(argv: list[str]) -> int:
    if len(argv) > 1:
        print("usage: python -m brdfkit.examples [NAME]", file=sys.stderr)
        return 2
    try:
        for name in argv or FILES:
            print(path(name))
    except ValueError as e:
        print(f"brdfkit: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
