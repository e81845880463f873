"""The ``brdfkit`` command line (typer + rich).

Core commands (``list``, ``info``, ``eval``) live here; each area adds its own
commands through a ``register(app)`` function in the module listed in
``_PLUGINS``. :func:`main` turns every ``ValueError`` / ``OSError`` into one
line on stderr and a non-zero exit — never a traceback.
"""

from __future__ import annotations

import importlib
import sys

import typer

app = typer.Typer(
    name="brdfkit",
    help="brdfkit: every BRDF of the classic lecture, exact, checked, rendered, fitted.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)



@app.callback()
def _root() -> None:
    """brdfkit: every BRDF of the classic lecture, exact, checked, rendered, fitted."""


# Modules that add commands: each defines ``register(app: typer.Typer) -> None``.
_PLUGINS: tuple[str, ...] = (
    "brdfkit.cli_core",
)

for _mod in _PLUGINS:
    importlib.import_module(_mod).register(app)


class CLIError(Exception):
    """An error whose message is the whole story (printed as one line)."""


def _one_line(exc: BaseException) -> str:
    msg = str(exc).strip().splitlines()
    return msg[0] if msg else type(exc).__name__


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script.

    typer's standalone mode handles usage errors (exit 2, a short message);
    errors raised by brdfkit itself become one line on stderr and exit 2.
    """
    try:
        app(args=argv, prog_name="brdfkit", standalone_mode=True)
    except SystemExit as e:
        code = e.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except (ValueError, OSError, CLIError, KeyError) as e:
        typer.echo(f"brdfkit: error: {_one_line(e)}", err=True)
        return 2
    return 0


def run() -> None:
    """Console-script wrapper: exit with :func:`main`'s status."""
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    run()
