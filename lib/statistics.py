"""Statistics of correlated samples shared by dem/ (calibration points) and compare/ (plate records)."""
from __future__ import annotations

import numpy as np

#: Sokal's window: the sum stops at the first lag M >= SOKAL_C tau(M)
SOKAL_C = 5.0


def autocorrelation_time(y) -> float:
    """Integrated autocorrelation time in samples, tau = 1/2 + sum_k rho(k), summed up to Sokal's window
    (the first M >= SOKAL_C tau(M)); 1/2 for white noise (then blocks of 2 tau samples are independent)."""
    y = np.asarray(y, dtype=float) - np.mean(y)
    n = len(y)
    if n < 2 or not np.any(y):
        return 0.5
    f = np.fft.rfft(y, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[:n]
    rho = acf / acf[0]
    tau = 0.5 + np.cumsum(rho[1:])
    window = np.nonzero(np.arange(1, n) >= SOKAL_C * tau)[0]
    return float(max(0.5, tau[window[0]] if len(window) else tau[-1]))
