"""Batch fitting: every (material, model) fit of ``brdfkit fit --all-measured``, on local
processes or on a Dask distributed cluster, crash-safe and resumable.

    run_batch(models, sources, out_dir, scheduler="tcp://10.0.0.5:8786", resume=True, ...)

Each fit is one task, ``fit_task(job)``: it rebuilds the samples of its material itself
(deterministic: they depend only on the material, ``samples``, ``seed`` and the angle
limit; a small per-process cache shares them between the models of one material), so a
task can run on any worker, be retried anywhere, and always give the same result.

* Without ``scheduler`` the tasks run on a pool of local processes
  (:class:`concurrent.futures.ProcessPoolExecutor`, ``workers`` of them, default: the
  CPUs this process may use).
* With ``scheduler="tcp://HOST:PORT"`` they are submitted to that Dask distributed
  scheduler (``pip install 'brdfkit[cluster]'``). A worker that dies mid-task has its
  tasks rescheduled on the others by the scheduler (up to
  ``distributed.scheduler.allowed-failures`` times, 3 by default), so the table is still
  complete; since a task is a pure function of its job, it is identical to a local run.
  Connecting gives up after ``BRDFKIT_DASK_TIMEOUT`` seconds (30).

Results. As each fit finishes, the submitting process writes it atomically
(:mod:`brdfkit.fileio`) to ``out_dir/fits/<material>__<column>.json``; a crash or Ctrl-C
therefore loses at most the fits in flight. ``resume=True`` skips every job whose file is
already there with the same settings. When the batch ends (also on Ctrl-C: then with
blank cells), the tables are written from those files: ``fit_errors.csv`` (columns
``material,<model>,...``), ``fit_params.json`` (one object per fit, the fields of
:meth:`~brdfkit.measured.result.FitResult.to_json` plus ``column``), ``fit_errors.md``
(the table, median/mean/best-on rows, mean rank, and every fit that ended on a fitting
bound), ``fit_errors_sorted.png`` (each model's errors sorted) and
``fit_errors_by_material.png`` (all models per material, materials sorted by the best
model's error; the form of Ngan et al. 2005's plots).
"""

from __future__ import annotations

import json
import math
import os
import re
import sys
import time
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from ..fileio import check_output_path, write_json, write_text, atomic_path
from .result import FitResult


# --------------------------------------------------------------------------- jobs
@dataclass(frozen=True)
class Job:
    """One fit: ``model`` (registry name) to ``source``, shown in the table as ``column``."""

    source: str
    model: str
    column: str
    fixed: tuple[tuple[str, Any], ...] = ()
    metric: str = "ngan"
    samples: int | str = 3000
    starts: int = 4
    seed: int = 0
    lobes: int = 1
    max_theta_deg: float = 80.0

    def settings(self) -> dict[str, Any]:
        """What a stored result must match to be reused by ``resume``."""
        from ..params import to_jsonable

        return {"model": self.model, "fixed": to_jsonable(dict(self.fixed)), "metric": self.metric,
                "samples": self.samples, "starts": self.starts, "seed": self.seed, "lobes": self.lobes,
                "max_theta_deg": self.max_theta_deg}

    def file_name(self) -> str:
        return _safe(self.source) + "__" + _safe(self.column) + ".json"


def _safe(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9._+-]", "-", s.replace("/", "--"))


@lru_cache(maxsize=4)
def _data(source: str, samples: int | str, seed: int, max_theta_deg: float):
    from .samples import sample, table

    if samples == "table":
        return table(source, max_theta_deg)
    return sample(source, n=samples, seed=seed, max_theta_deg=max_theta_deg)


def fit_task(job: Job) -> dict[str, Any]:
    """Run one fit (in a worker); returns the JSON record stored for it."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    from .optimise import fit

    data = _data(job.source, job.samples, job.seed, job.max_theta_deg)
    r = fit(job.model, job.source, fixed=dict(job.fixed), metric=job.metric, starts=job.starts,
            samples=job.samples, seed=job.seed, lobes=job.lobes, max_theta_deg=job.max_theta_deg, data=data)
    rec = r.to_json()
    rec["column"] = job.column
    rec["settings"] = job.settings()
    return rec


def make_jobs(columns: Iterable[str], sources: Iterable[str], fixed: Mapping[str, Mapping[str, Any]] | None = None,
              names: Mapping[str, str] | None = None, **settings: Any) -> list[Job]:
    """The jobs of a batch, material-major (so a worker's cache serves a material's models).

    ``columns``: the table's column labels; ``names[label]`` the registry model of a column
    (default: the label itself); ``fixed[label]`` its fixed parameters."""
    fixed = fixed or {}
    names = names or {}
    jobs = []
    for s in sources:
        for c in columns:
            fx = tuple(sorted((k, _hashable(v)) for k, v in (fixed.get(c) or {}).items()))
            jobs.append(Job(s, names.get(c, c), c, fx, **settings))
    return jobs


def _hashable(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return tuple(float(x) for x in v.ravel())
    if isinstance(v, list):
        return tuple(v)
    return v


# --------------------------------------------------------------------------- in one process
def fit_batch(
    names: Iterable[str],
    sources: Iterable[str],
    metric: str = "ngan",
    fixed: Mapping[str, Mapping[str, Any]] | None = None,
    progress: bool = True,
    **kw: Any,
) -> list[FitResult]:
    """Fit every model in ``names`` to every source, one after the other in this process (no
    files written; :func:`run_batch` is the crash-safe, parallel batch); the samples of a source
    are shared by the models. ``kw``: :func:`~brdfkit.measured.optimise.fit`'s keywords."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from .optimise import fit
    from .samples import sample, table

    names = list(names)
    sources = list(sources)
    fixed = fixed or {}
    out: list[FitResult] = []
    samp_kw = {k: kw.pop(k) for k in ("samples", "seed", "max_theta_deg") if k in kw}
    n_samp = samp_kw.pop("samples", 3000)
    log_lines = progress and not sys.stderr.isatty()  # a log file: one plain line per material
    t0 = time.perf_counter()
    with Progress(
        TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
        TimeRemainingColumn(), console=Console(stderr=True), disable=not progress or log_lines,
    ) as bar:
        task = bar.add_task("fitting", total=len(names) * len(sources))
        for n_src, src in enumerate(sources, 1):
            if log_lines:
                print(f"[{n_src}/{len(sources)}] {src} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
            data = (table(src, samp_kw.get("max_theta_deg", 80.0)) if n_samp == "table"
                    else sample(src, n=n_samp, **samp_kw))
            for nm in names:
                bar.update(task, description=f"{nm:>18} ← {data.source}")
                out.append(fit(nm, src, fixed=fixed.get(nm), metric=metric, data=data, samples=n_samp,
                               seed=samp_kw.get("seed", 0), **kw))
                bar.update(task, advance=1)
    return out


# --------------------------------------------------------------------------- the store
def _load_done(fits_dir: Path, jobs: list[Job]) -> dict[Job, dict[str, Any]]:
    done = {}
    for j in jobs:
        p = fits_dir / j.file_name()
        if not p.is_file():
            continue
        try:
            rec = json.loads(p.read_text())
        except (OSError, ValueError):
            continue  # unreadable: fit it again
        if rec.get("settings") == json.loads(json.dumps(j.settings())):
            done[j] = rec
    return done


@dataclass
class BatchOutcome:
    """What :func:`run_batch` did: the records (in job order; None where missing), counts, files."""

    jobs: list[Job]
    records: list[dict[str, Any] | None]
    fitted: int = 0
    skipped: int = 0
    seconds: float = 0.0
    files: dict[str, str] = field(default_factory=dict)
    at_bound: list[str] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        return all(r is not None for r in self.records)


def run_batch(
    models: list[str],
    sources: list[str],
    out_dir: str | os.PathLike,
    *,
    names: Mapping[str, str] | None = None,
    fixed: Mapping[str, Mapping[str, Any]] | None = None,
    metric: str = "ngan",
    samples: int | str = 3000,
    starts: int = 4,
    seed: int = 0,
    lobes: int = 1,
    max_theta_deg: float = 80.0,
    scheduler: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    progress: Callable[[int, int, dict[str, Any]], None] | None = None,
    tables: bool = True,
) -> BatchOutcome:
    """Fit every model to every source (see the module docstring); returns a :class:`BatchOutcome`.

    ``models``: the column labels; ``names`` maps a label to its registry model where they
    differ (``{"ward-dur": "ward"}`` with ``fixed={"ward-dur": {"normalization": "dur"}}``)."""
    t0 = time.perf_counter()
    out = check_output_path(out_dir, what="batch output", is_dir=True)
    out.mkdir(exist_ok=True)
    fits_dir = out / "fits"
    fits_dir.mkdir(exist_ok=True)
    jobs = make_jobs(models, sources, fixed, names, metric=metric, samples=samples, starts=starts, seed=seed,
                     lobes=lobes, max_theta_deg=max_theta_deg)
    done = _load_done(fits_dir, jobs) if resume else {}
    todo = [j for j in jobs if j not in done]
    outcome = BatchOutcome(jobs, [done.get(j) for j in jobs], skipped=len(done))
    index = {j: i for i, j in enumerate(jobs)}

    def finished(job: Job, rec: dict[str, Any]) -> None:
        write_json(fits_dir / job.file_name(), rec, indent=1)
        outcome.records[index[job]] = rec
        outcome.fitted += 1
        if progress is not None:
            progress(outcome.fitted + outcome.skipped, len(jobs), rec)

    try:
        if todo:
            if scheduler:
                _run_dask(todo, scheduler, finished)
            else:
                _run_local(todo, workers, finished)
    finally:
        outcome.seconds = time.perf_counter() - t0
        if tables:
            outcome.files = write_tables(outcome.records, jobs, list(dict.fromkeys(j.column for j in jobs)),
                                         list(dict.fromkeys(sources)), out, metric, outcome.seconds)
        outcome.at_bound = [f"{r['source']} {r['column']}: {', '.join(r['at_bound'])}"
                            for r in outcome.records if r and r.get("at_bound")]
    return outcome


def _ignore_sigint() -> None:
    """Pool workers leave Ctrl-C to the parent (which writes what finished and stops them)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


_ONE_THREAD = {"OMP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}


def _run_local(todo: list[Job], workers: int | None, finished) -> None:
    import concurrent.futures as cf
    import multiprocessing as mp

    n = workers or len(os.sched_getaffinity(0))
    if n < 1:
        raise ValueError(f"workers must be at least 1, got {n}")
    if n == 1:  # in-process: no pool to start
        for j in todo:
            finished(j, fit_task(j))
        return
    # one BLAS and one numba thread per worker process: the pool already runs one fit per core.
    # The pool spawns its processes as tasks are submitted, so the environment they inherit is
    # set until every task is.
    env_before = {k: os.environ.get(k) for k in _ONE_THREAD}
    futs = {}
    ex = None
    try:
        os.environ.update(_ONE_THREAD)
        try:
            ex = cf.ProcessPoolExecutor(max_workers=min(n, len(todo)), mp_context=mp.get_context("spawn"),
                                        initializer=_ignore_sigint)
            futs = {ex.submit(fit_task, j): j for j in todo}
        finally:
            for k, v in env_before.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        for f in cf.as_completed(futs):
            finished(futs[f], f.result())
    finally:
        for f in futs:
            f.cancel()
        if ex is not None:
            ex.shutdown(wait=True, cancel_futures=True)


def _run_dask(todo: list[Job], scheduler: str, finished) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:  # pragma: no cover - the extra is installed in CI
        raise ValueError("--scheduler needs Dask distributed: pip install 'brdfkit[cluster]'") from None
    if not re.match(r"^[a-z]+://[^\s/:]+:\d+$", scheduler):
        raise ValueError(f"--scheduler must look like tcp://HOST:PORT, got {scheduler!r}")
    try:
        client = Client(scheduler, timeout=float(os.environ.get("BRDFKIT_DASK_TIMEOUT", "30")), set_as_default=True)
    except (OSError, TimeoutError) as e:
        raise ValueError(f"cannot connect to the Dask scheduler at {scheduler}: {e}") from None
    futs = []
    try:
        futs = client.map(fit_task, todo, pure=False, key=[f"fit-{j.file_name()[:-5]}" for j in todo])
        which = {f.key: j for f, j in zip(futs, todo)}
        for f in as_completed(futs):
            finished(which[f.key], f.result())
    finally:
        if futs:
            client.cancel(futs)
        client.close()


# --------------------------------------------------------------------------- tables
def mean_ranks(errs: np.ndarray) -> np.ndarray:
    """Mean rank (1 = best) of each column over the rows without a missing value; ties share ranks."""
    from scipy.stats import rankdata

    rows = errs[np.isfinite(errs).all(axis=1)]
    if rows.size == 0:
        return np.full(errs.shape[1], np.nan)
    return rankdata(rows, axis=1).mean(axis=0)


def write_tables(records, jobs: list[Job], columns: list[str], sources: list[str], out_dir, metric: str,
                 seconds: float) -> dict[str, str]:
    """The batch's CSV, Markdown, plots and JSON from its records (None = not fitted: blank cell)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    by = {(j.source, j.column): r for j, r in zip(jobs, records)}
    errs = np.array([[by[(s, c)]["error"] if by.get((s, c)) else np.nan for c in columns] for s in sources],
                    dtype=float).reshape(len(sources), len(columns))
    n_done = int(np.isfinite(errs).sum())
    files = {}

    lines = ["material," + ",".join(columns)]
    for s, row in zip(sources, errs):
        lines.append(s + "," + ",".join("" if not math.isfinite(e) else f"{e:.6g}" for e in row))
    files["csv"] = str(out / "fit_errors.csv")
    write_text(files["csv"], "\n".join(lines) + "\n")

    complete = np.isfinite(errs).all(axis=1)
    best = np.where(complete, np.nanargmin(np.where(np.isfinite(errs), errs, np.inf), axis=1), -1)
    ranks = mean_ranks(errs)
    md = [f"Fitting error per material and model; metric: {metric}. Best per row in bold.", "",
          "| material | " + " | ".join(columns) + " |", "|---|" + "---:|" * len(columns)]
    for i, s in enumerate(sources):
        cells = ["—" if not math.isfinite(e) else (f"**{e:.4g}**" if j == best[i] else f"{e:.4g}")
                 for j, e in enumerate(errs[i])]
        md.append(f"| {s} | " + " | ".join(cells) + " |")

    def stat(fn):
        return " | ".join("—" if not np.isfinite(errs[:, j]).any() else f"{fn(errs[np.isfinite(errs[:, j]), j]):.4g}"
                          for j in range(len(columns)))

    md.append("| **median** | " + stat(np.median) + " |")
    md.append("| **mean** | " + stat(np.mean) + " |")
    md.append("| **mean rank** | " + " | ".join("—" if not math.isfinite(r) else f"{r:.2f}" for r in ranks) + " |")
    md.append("| **best on** | " + " | ".join(str(int((best == j).sum())) for j in range(len(columns))) + " |")
    md.append("")
    md.append(f"{n_done} of {len(sources) * len(columns)} fits ({len(sources)} materials × {len(columns)} models); "
              f"this run took {seconds:.0f} s. Mean rank over the {int(complete.sum())} materials with every model "
              "fitted (1 = best).")
    bound = [(r["source"], r["column"], r["at_bound"]) for r in records if r and r.get("at_bound")]
    md.append("")
    if bound:
        md.append(f"Fits that ended on a fitting bound ({len(bound)}; `at_bound` in fit_params.json):")
        md.append("")
        for s, c, ab in bound:
            md.append(f"- {s}, {c}: {', '.join(ab)}")
    else:
        md.append("No fit ended on a fitting bound.")
    files["markdown"] = str(out / "fit_errors.md")
    write_text(files["markdown"], "\n".join(md) + "\n")

    fig, ax = plt.subplots(figsize=(8.5, 5), dpi=110)
    for j, c in enumerate(columns):
        e = np.sort(errs[np.isfinite(errs[:, j]), j])
        if e.size:
            ax.plot(np.arange(1, e.size + 1), e, label=f"{c} (mean rank {ranks[j]:.2f})", lw=1.6)
    ax.set_yscale("log")
    ax.set_xlabel("materials, sorted by error (per model)")
    ax.set_ylabel(f"fitting error ({metric})")
    ax.set_title(f"Fit of {len(columns)} analytic models to {len(sources)} measured materials")
    ax.grid(True, which="both", alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    fig.tight_layout()
    files["plot"] = str(out / "fit_errors_sorted.png")
    with atomic_path(files["plot"]) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(11, 5), dpi=110)
    key = np.where(np.isfinite(errs), errs, np.inf).min(axis=1)
    order = np.argsort(key)
    for j, c in enumerate(columns):
        ax.plot(np.arange(1, len(sources) + 1), errs[order, j], marker="o", ms=2.5, lw=0.6, label=c)
    ax.set_yscale("log")
    ax.set_xlabel("materials, sorted by the best model's error")
    ax.set_ylabel(f"fitting error ({metric})")
    ax.set_title("Every model on every material")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    files["plot_by_material"] = str(out / "fit_errors_by_material.png")
    with atomic_path(files["plot_by_material"]) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)

    files["params"] = str(out / "fit_params.json")
    write_json(files["params"], [r for r in records if r], indent=1)
    return files


__all__ = ["Job", "BatchOutcome", "fit_task", "fit_batch", "make_jobs", "run_batch", "write_tables", "mean_ranks"]
