"""The near-equilibrium estimator of the configuration-space KL divergence
(rigidtesting.samplingerror.configurationKL, which benchmarks/studies/sampling_error.py uses) on a
1-D harmonic oscillator, where each Langevin splitting's sampled distribution is a known Gaussian
(the stationary covariance of its linear step): OBABO's configurations are too wide by
1/(1 - (omega dt)^2/4), BAOAB's exact. The estimate agrees with the exact divergence within 4 of its
standard errors, and tells OBABO's from zero."""

import numpy as np
import pytest

from rigidtesting.samplingerror import configurationKL, harmonicConfigurationKL, harmonicLangevinSamples
import rigidtesting


@pytest.mark.parametrize("splitting", ["O V R V O", "V R O R V"])
def test_estimate_matches_the_exact_divergence(splitting):
    omega, dt, friction = 1.0, 1.0, 1.0
    exact = harmonicConfigurationKL(splitting, omega, dt, friction)
    fromEquilibrium, fromResampled = harmonicLangevinSamples(splitting, omega, dt, friction, steps=20, samples=100000, seed=3)
    estimate, error = configurationKL(fromEquilibrium, fromResampled)
    print(f"{splitting}: exact {exact:.5f}, estimate {estimate:.5f} +- {error:.5f}")
    assert abs(estimate - exact) < 4 * error
    if splitting == "O V R V O":
        ratio = 1 / (1 - (omega * dt) ** 2 / 4)
        assert exact == pytest.approx(0.5 * (ratio - 1 - np.log(ratio)), rel=1e-9)  # the closed form for OBABO
        assert estimate > 10 * error
    else:
        assert exact == pytest.approx(0.0, abs=1e-12)


def test_bad_input():
    with pytest.raises(ValueError, match="configurationKL"):
        configurationKL([1.0, 2.0], [1.0])
