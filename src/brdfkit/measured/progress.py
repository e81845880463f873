"""The progress of one fit (or one tabulation): a transient bar of its steps on a terminal, and/or a callback.

The bar is drawn on standard error, and only when that is a terminal: the fit's own output
(``brdfkit fit``'s text or JSON on standard output) stays exactly what it prints (rich's live
display, stopped on a console that is not a terminal, would leave an empty line there).
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Callable, Iterator


def _bar(title: str, total: int, unit: str = "starts"):
    """A started rich progress bar of ``total`` steps (named ``unit``) on a terminal's standard error, and its
    task; ``None`` when standard error is not a terminal."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    if not console.is_terminal:
        return None
    bar = Progress(
        TextColumn(title), BarColumn(), TextColumn("{task.completed}/{task.total} " + unit),
        TimeElapsedColumn(), console=console, transient=True,
    )
    bar.start()
    return bar, bar.add_task("fit", total=total)


@contextmanager
def fit_progress(progress: bool | Callable[[int, int], None], title: str, total: int,
                 unit: str = "starts") -> Iterator[Callable[[int], None]]:
    """``step(done)``, to call as each of ``total`` steps (local starts, a polish) ends;
    ``step.total(n)`` raises the number of steps to ``n``.

    ``progress``: ``True`` for the bar (titled ``title``), a callable ``(done, total)`` called at
    every step, or ``False`` for neither. The bar is taken down on leaving, also on an error."""
    callback = progress if callable(progress) else None
    shown = _bar(title, total, unit) if progress is True else None

    def step(done: int) -> None:
        if shown is not None:
            shown[0].update(shown[1], advance=1)
        if callback is not None:
            callback(done, total)

    def grow(new_total: int) -> None:
        """More steps than announced (a fit that searches on): the bar's and the callback's total."""
        nonlocal total
        total = new_total
        if shown is not None:
            shown[0].update(shown[1], total=new_total)

    step.total = grow

    try:
        yield step
    finally:
        if shown is not None:
            shown[0].stop()


__all__ = ["fit_progress"]
