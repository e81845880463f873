"""An independent reference for the HTSG series (He et al. 1991, eq. 78): mpmath, 40 digits.

Shared by test_htsg.py and test_reliability_docs.py; imports mpmath, so import it where mpmath is present.
"""

from __future__ import annotations

import mpmath


def mp_series(g: float, T: float) -> mpmath.mpf:
    """Σ_{m≥1} e^-g g^m/(m! m) e^(-T/m) in 40-digit arithmetic, summed until the terms are negligible."""
    with mpmath.workdps(40):
        g, T = mpmath.mpf(g), mpmath.mpf(T)
        s, m, peak = mpmath.mpf(0), 1, mpmath.mpf(0)
        while True:
            t = mpmath.exp(-g + m * mpmath.log(g) - mpmath.loggamma(m + 1) - T / m) / m
            s += t
            peak = max(peak, t)
            if m > g + 10 and m * m > T and t < peak * mpmath.mpf(10) ** -30:
                return s
            m += 1
