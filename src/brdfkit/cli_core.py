"""Core commands: ``list``, ``info``, ``eval`` (to be completed)."""

from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    @app.command("list")
    def list_models() -> None:
        """List the models."""
        import brdfkit as bk

        for n in bk.models():
            typer.echo(n)
