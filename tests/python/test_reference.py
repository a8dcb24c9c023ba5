"""Checks of the independent reference (reference.py) itself, before it is used to judge
openmmrigid: the paper's Section 5 values, closed-form spherical and symmetric tops, the
textbook closed form of omega(t), and the conservation laws."""

import itertools

import numpy as np
import pytest

import reference
from paper_example import (PAPER_ATTITUDE, PAPER_MOMENTS, PAPER_OMEGA, PAPER_VALUES,
                           PRECISE_VALUES)


@pytest.mark.parametrize("t", [1.0, 10.0])
def test_reference_reproduces_paper_example(t):
    omega, attitude = reference.integrate(PAPER_MOMENTS, PAPER_OMEGA, PAPER_ATTITUDE, [t])
    for values, tol in ((PAPER_VALUES, 1e-11), (PRECISE_VALUES, 1e-11)):
        expected_omega, expected_attitude = values[t]
        assert np.abs(omega[0] - expected_omega).max() <= tol * np.linalg.norm(PAPER_OMEGA)
        assert np.abs(attitude[0] - expected_attitude).max() <= tol


@pytest.mark.parametrize("t", [0.0, 1.0, 10.0])
def test_closed_form_reproduces_precise_paper_omega(t):
    omega = reference.omega_closed_form(PAPER_MOMENTS, PAPER_OMEGA, t)
    expected = PRECISE_VALUES[t][0] if t else np.asarray(PAPER_OMEGA, dtype=float)
    assert np.abs(omega - expected).max() <= 1e-15 * np.linalg.norm(PAPER_OMEGA)


@pytest.mark.parametrize("permutation", list(itertools.permutations(range(3))))
def test_reference_matches_closed_form_omega(permutation):
    rng = np.random.default_rng(sum(10**k * p for k, p in enumerate(permutation)))
    moments = np.sort(rng.uniform(0.5, 3.0, 3))[list(permutation)]
    omega = rng.normal(size=3)
    times = np.array([0.3, 2.0, 7.0]) * 2 * np.pi / np.linalg.norm(omega)
    integrated, _ = reference.integrate(moments, omega, reference.random_rotation(rng), times)
    for k, t in enumerate(times):
        exact = reference.omega_closed_form(moments, omega, t)
        assert np.abs(integrated[k] - exact).max() <= 1e-12 * np.linalg.norm(omega)


@pytest.mark.parametrize("scale", [1e-8, 1.0, 1e8])
def test_reference_spherical_top_is_steady_rotation(scale):
    rng = np.random.default_rng(7)
    omega = rng.normal(size=3) * scale
    attitude = reference.random_rotation(rng)
    times = np.array([0.1, 3.0, 20.0]) / scale
    integrated_omega, integrated_attitude = reference.integrate([2.0, 2.0, 2.0], omega, attitude,
                                                                times)
    for k, t in enumerate(times):
        assert np.abs(integrated_omega[k] - omega).max() <= 1e-14 * np.linalg.norm(omega)
        exact = reference.steady_rotation(omega, attitude, t)
        assert np.abs(integrated_attitude[k] - exact).max() <= 1e-12


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("unique", [0.5, 2.0])
def test_reference_symmetric_top_matches_closed_form(axis, unique):
    rng = np.random.default_rng(11 + axis)
    moments = np.full(3, 1.3)
    moments[axis] *= unique
    omega = rng.normal(size=3)
    attitude = reference.random_rotation(rng)
    times = np.array([0.2, 1.0, 3.0]) * 2 * np.pi / np.linalg.norm(omega)
    integrated_omega, integrated_attitude = reference.integrate(moments, omega, attitude, times)
    for k, t in enumerate(times):
        exact_omega, exact_attitude = reference.symmetric_top(moments, omega, attitude, t, axis)
        assert np.abs(integrated_omega[k] - exact_omega).max() <= 1e-12 * np.linalg.norm(omega)
        assert np.abs(integrated_attitude[k] - exact_attitude).max() <= 1e-12


def test_reference_conserves_invariants_and_runs_backwards():
    rng = np.random.default_rng(5)
    moments = np.array([1.0, 2.7, 1.9])
    omega = rng.normal(size=3)
    attitude = reference.random_rotation(rng)
    times = np.array([-4.0, -0.5, 0.0, 0.5, 4.0]) * 2 * np.pi / np.linalg.norm(omega)
    omegas, attitudes = reference.integrate(moments, omega, attitude, times)
    lab = attitude.T @ (moments * omega)
    for w, a in zip(omegas, attitudes):
        assert abs(np.sum(moments * w**2) / np.sum(moments * omega**2) - 1) <= 1e-13
        assert np.abs(a.T @ (moments * w) - lab).max() <= 1e-12 * np.linalg.norm(lab)
        assert np.abs(a @ a.T - np.eye(3)).max() <= 1e-12
    # forward then backward returns to the start
    w1, a1 = reference.integrate(moments, omega, attitude, [times[-1]])
    w2, a2 = reference.integrate(moments, w1[0], a1[0], [-times[-1]])
    assert np.abs(w2[0] - omega).max() <= 1e-12 * np.linalg.norm(omega)
    assert np.abs(a2[0] - attitude).max() <= 1e-12


def test_separatrix_helpers():
    moments = np.array([3.7, 1.3, 2.1])
    for offset in (0.0, 1e-6, -1e-10, 1e-14):
        omega = reference.near_separatrix_omega(moments, [0.8, 1.1, 0.5], offset)
        assert abs(reference.separatrix_offset(moments, omega) - offset) <= 1e-15
    assert reference.separatrix_offset([2.0, 3.0, 6.0], [3.0, 5.0, 1.0]) == 0.0
    assert reference.exact_parameter([2.0, 3.0, 6.0], [3.0, 5.0, 1.0]) == 1
    assert reference.exact_parameter([2.0, 3.0, 6.0], [0.0, 0.0, 1.0]) == 0
