"""The ``brdfkit`` command line (typer + rich).

Core commands (``list``, ``info``, ``eval``) live in :mod:`brdfkit.cli_core`; each
area adds its own commands through a ``register(app)`` function in the module listed in
``_PLUGINS``, imported only when a command of it runs (:func:`load_commands`). :func:`main` turns every error (usage errors, ``ValueError`` /
``OSError`` for bad input, and anything unexpected) into one line on stderr and
a non-zero exit — never a traceback (``BRDFKIT_DEBUG=1`` shows the traceback of
an unexpected error).
"""

from __future__ import annotations

import importlib
import os
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


def _show_version(value: bool) -> None:
    if value:
        from ._version import __version__

        typer.echo(f"brdfkit {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", is_eager=True, callback=_show_version, help="Print brdfkit's version and exit."
    ),
) -> None:
    """brdfkit: every BRDF of the classic lecture, exact, checked, rendered, fitted."""


# Modules that add commands: each defines ``register(app: typer.Typer) -> None``.
_PLUGINS: tuple[str, ...] = (
    "brdfkit.cli_core",
    "brdfkit.analysis.commands",
    "brdfkit.measured.commands",
    "brdfkit.render.commands",
    "brdfkit.web.commands",
    "brdfkit.interchange.commands",
)

#: each command's plugin, so that a run imports only the plugin of the command it runs (``brdfkit
#: eval`` then skips the renderer, the web server and their imports: ~0.1 s of a ~1 s start);
#: ``tests/test_cli_core.py`` checks this table against what every plugin registers
COMMANDS: dict[str, str] = {
    "list": "brdfkit.cli_core",
    "info": "brdfkit.cli_core",
    "eval": "brdfkit.cli_core",
    "check": "brdfkit.analysis.commands",
    "plot": "brdfkit.analysis.commands",
    "fit": "brdfkit.measured.commands",
    "tabulate": "brdfkit.measured.commands",
    "render": "brdfkit.render.commands",
    "gallery": "brdfkit.render.commands",
    "serve": "brdfkit.web.commands",
    "export": "brdfkit.interchange.commands",
}
_REGISTERED: set[str] = set()


def load_commands(argv: list[str] | None = None) -> typer.Typer:
    """Register the plugin of the command named in ``argv`` (default ``sys.argv[1:]``) on :data:`app`,
    or every plugin when there is none or it is not in :data:`COMMANDS` (``--help``, ``--version``,
    a misspelt name: the full list then appears in the help or the error). Returns :data:`app`."""
    args = sys.argv[1:] if argv is None else list(argv)
    name = next((a for a in args if not a.startswith("-")), None)
    wanted = (COMMANDS[name],) if name in COMMANDS else _PLUGINS
    for mod in wanted:
        if mod not in _REGISTERED:
            importlib.import_module(mod).register(app)
            _REGISTERED.add(mod)
    return app


def _one_line(exc: BaseException) -> str:
    msg = str(exc).strip().splitlines()
    return msg[0] if msg else type(exc).__name__


def _usage_hint(exc: BaseException) -> str:
    ctx = getattr(exc, "ctx", None)
    path = getattr(ctx, "command_path", None) or "brdfkit"
    return f" (see '{path} --help')"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status.

    Every error becomes ONE line on stderr, ``brdfkit: error: ...``, and a
    non-zero status — never a traceback: usage errors from the option parser
    (unknown option, missing argument: status 2) as well as the ``ValueError``
    / ``OSError`` raised by brdfkit itself for bad values or files (status 2).
    ``--help`` and ``typer.Exit(code)`` keep their status. Any other exception
    (a bug, a missing GL driver) is one line too, ``brdfkit: internal error: ...``,
    status 1; set ``BRDFKIT_DEBUG=1`` to get the traceback instead.
    """
    try:
        load_commands(argv)
        rv = app(args=argv, prog_name="brdfkit", standalone_mode=False)
    except SystemExit as e:
        code = e.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except (ValueError, OSError, KeyError) as e:
        typer.echo(f"brdfkit: error: {_one_line(e)}", err=True)
        return 2
    except typer.Abort:
        typer.echo("brdfkit: aborted", err=True)
        return 1
    except Exception as e:
        # click/typer usage errors (ClickException and subclasses): duck-typed, since
        # their class lives in click or in typer's vendored copy depending on the version.
        fmt = getattr(e, "format_message", None)
        code = getattr(e, "exit_code", None)
        if type(e).__name__ == "NoArgsIsHelpError":  # bare `brdfkit` / group: show the help
            ctx = getattr(e, "ctx", None)
            typer.echo(ctx.get_help() if ctx is not None else fmt())
            return 0
        if callable(fmt) and isinstance(code, int):
            msg = _one_line(Exception(fmt()))
            typer.echo(f"brdfkit: error: {msg}{_usage_hint(e)}", err=True)
            return code or 1
        if os.environ.get("BRDFKIT_DEBUG"):
            raise
        # anything else is a bug or an environment problem (no GL driver...): still one line
        typer.echo(
            f"brdfkit: internal error: {type(e).__name__}: {_one_line(e)} (set BRDFKIT_DEBUG=1 for the traceback)",
            err=True,
        )
        return 1
    # Without standalone mode, typer returns an explicit Exit's code (an int) or the
    # command's return value (None for every brdfkit command).
    return rv if isinstance(rv, int) and not isinstance(rv, bool) else 0


def run() -> None:
    """Console-script wrapper: exit with :func:`main`'s status.

    The process is brdfkit's own, so numba's import-time BLAS probe is skipped first
    (:func:`brdfkit.engine.skip_blas_probe`: 0.1-0.3 s of every command that evaluates).
    """
    from .engine import skip_blas_probe

    skip_blas_probe()
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    run()
