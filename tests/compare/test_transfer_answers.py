"""The calibration's transfer error to the drives (compare.comparison.transfer_sd, with_transfer).

* transfer_sd: flowing pairs (I >= TRANSFER_I_MIN) with residuals +-0.02, pair errors 0.01 and law spread 0.005:
  sqrt(0.02^2 - 0.01^2 - 0.005^2) = 0.01658; slow pairs (I below it) 0.1 under the law change nothing; residuals
  inside their errors give 0; no flowing pair gives 0.
* with_transfer: 200 replicates moved by sd = 0.03 shift mu_s and mu_d by the same amount (mu_d - mu_s, I0 and phi
  unchanged), the shifts' mean is 0 and their standard deviation sd to 1 % (normal quantiles), either half of the
  replicates holds both signs, and the replicates' covariance of mu_s grows by sd^2 (to the shifts' own spread).
"""
import numpy as np
import pandas as pd
import pytest
from granstokes.compare.comparison import TRANSFER_I_MIN, transfer_sd, with_transfer


def test_the_transfer_error_is_the_flowing_pairs_excess_over_their_errors():
    I = np.array([TRANSFER_I_MIN, 0.1, 0.2, 0.3, 0.5 * TRANSFER_I_MIN, 0.1 * TRANSFER_I_MIN])
    resid = np.array([0.02, -0.02, 0.02, -0.02, -0.1, -0.1])
    s_pair, s_law = np.full(6, 0.01), np.full(6, 0.005)
    assert transfer_sd(I, resid, s_pair, s_law) == pytest.approx(np.sqrt(0.02**2 - 0.01**2 - 0.005**2), rel=1e-12)
    assert transfer_sd(I, resid, s_pair, s_law) == pytest.approx(0.016583, abs=1e-6)
    assert transfer_sd(I, resid / 4, s_pair, s_law) == 0.0  # residuals inside their errors
    assert transfer_sd(I[4:], resid[4:], s_pair[4:], s_law[4:]) == 0.0  # no flowing pair


def test_the_transfer_moves_the_whole_law_and_widens_the_replicates_by_its_sd():
    n, sd = 200, 0.03
    rng = np.random.default_rng(5)
    reps = pd.DataFrame({"mu_s": 0.38 + 0.005 * rng.standard_normal(n), "mu_d": 0.7 + 0.02 * rng.standard_normal(n),
                         "I0": np.full(n, 0.3), "phi": np.full(n, 0.8)})
    moved = with_transfer(reps, sd)
    shift = (moved.mu_s - reps.mu_s).to_numpy()
    assert np.allclose(moved.mu_d - reps.mu_d, shift, atol=1e-15, rtol=0)
    assert (moved.I0 == reps.I0).all() and (moved.phi == reps.phi).all()
    assert abs(shift.mean()) < 1e-15 and shift.std(ddof=1) == pytest.approx(sd, rel=0.01)
    assert (shift[: n // 2] > 0).any() and (shift[: n // 2] < 0).any()
    assert moved.mu_s.var(ddof=1) == pytest.approx(reps.mu_s.var(ddof=1) + shift.var(ddof=1), rel=0.1)
    assert moved.mu_s.var(ddof=1) > 20 * reps.mu_s.var(ddof=1)
    assert with_transfer(reps, sd).equals(moved) and with_transfer(reps, 0.0).equals(reps)
