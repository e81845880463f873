"""Serial or parallel: each driver's work per pair, estimated from its own earlier calls.

A parallel launch on numba's thread pool costs more than a fitter's evaluation of 3000 samples, so a
call whose estimated work is below :data:`PARALLEL_MIN_S` runs the driver's serial twin on the calling
thread (:func:`serially`); so does every call where numba has one thread. The estimate of a driver
(by its key, :mod:`.generated`) is the one-thread seconds per pair of its latest call of more than one
chunk after its first (:func:`record`): a parallel call's time times its threads, an upper bound.
"""

from __future__ import annotations

import numba

from .templates import CHUNK

#: a call whose work, estimated from the driver's earlier calls, is below this many seconds on one
#: thread runs serially. Measured here (2 cores, load 0.5), serial / parallel: GGX microfacet 3000
#: pairs 0.14 / 0.38 ms, 48 000 pairs 1.3 / 1.7 ms, 96 000 pairs 2.4 / 2.2 ms; Lambert 96 000 pairs
#: 0.44 / 0.59 ms; HTSG 3000 pairs 4.6 / 3.1 ms: a launch on numba's workqueue layer costs ~0.2-0.5 ms
#: (measured on workqueue, before the TBB layer became the default: not yet measured again on TBB)
PARALLEL_MIN_S = 2e-3
#: seconds per pair on one thread, measured on each driver's calls after its first (by key)
_PAIR_COST: dict[tuple, float] = {}


def serially(key: tuple, n: int) -> tuple[bool, int]:
    """``(serial, threads)``: whether a call of ``n`` pairs runs the serial twin of the driver ``key`` (one
    numba thread, or work estimated from its earlier calls below :data:`PARALLEL_MIN_S`)."""
    threads = numba.get_num_threads()
    cost = _PAIR_COST.get(key)
    return threads == 1 or (cost is not None and n * cost < PARALLEL_MIN_S), threads


def record(key: tuple, elapsed: float, serial: bool, threads: int, n: int) -> None:
    """Note a call's seconds per pair on one thread (calls of more than :data:`CHUNK` pairs only)."""
    if n > CHUNK:
        _PAIR_COST[key] = elapsed * (1 if serial else threads) / n


__all__ = ["PARALLEL_MIN_S", "serially", "record"]
