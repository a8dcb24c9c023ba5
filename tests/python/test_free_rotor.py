"""Tests of openmmrigid.FreeRotor, the exact free rigid-body rotation of van Zon & Schofield,
J. Comput. Phys. 225 (2007) 145, against known answers:

- the paper's Section 5 example;
- an independent integration of Euler's equations and dA/dt = -W(omega) A (reference.py);
- closed forms (steady rotation, spherical, symmetric and linear tops);
- the textbook closed form of omega(t) in 40-digit arithmetic (long times);
- conservation laws (energy, |L|, lab-frame L, orthonormality) and the flow property.

Tolerances: omega relative to |omega(0)|, the attitude matrix A absolute (|A_ij| <= 1).
Near the separatrix E = L^2/(2 I2) the problem itself is ill-conditioned (errors of any solution,
this one or the reference, grow like exp(lambda t) on the approach to the unstable middle axis),
so comparisons there stop at lambda t = 8, where the conditioning costs at most ~3e3 ulp.
"""

import itertools

import numpy as np
import openmm
import pytest

import openmmrigid
import reference
from paper_example import (PAPER_ATTITUDE, PAPER_MOMENTS, PAPER_OMEGA, PAPER_VALUES,
                           PRECISE_VALUES)

FreeRotor = openmmrigid.FreeRotor

REFERENCE_TOLERANCE = 1e-10     # vs. the reference integration (omega / |omega|, A)
ORTHONORMAL_TOLERANCE = 1e-13   # max |A A^T - 1|
CONSERVATION_TOLERANCE = 1e-13  # relative drift of E and |L| computed from the returned omega
LAB_MOMENTUM_TOLERANCE = 1e-12  # relative drift of L_lab = A^T I omega
ASYMMETRIC = ("theta-series", "elliptic-integral")

# Assignments of the (smallest, middle, largest) moments to the body axes x, y, z: the smallest
# first and last, the middle one in every slot.
SLOT_ORDERS = list(itertools.permutations(range(3)))


def arrange(sorted_moments, order):
    """Put sorted_moments[order[k]] on body axis k."""
    return np.asarray(sorted_moments, dtype=float)[list(order)]


def describe(moments, omega, attitude=None, t=None):
    text = f"moments={list(map(float, moments))!r}, omega={list(map(float, omega))!r}"
    if attitude is not None:
        text += f", attitude={np.asarray(attitude).tolist()!r}"
    if t is not None:
        text += f", t={np.asarray(t).tolist()!r}"
    return text


def rotation_period(omega):
    return 2 * np.pi / np.linalg.norm(omega)


def effective_omega(moments, omega):
    """omega with the component along a linear body's axis removed."""
    omega = np.array(omega, dtype=float)
    axis = reference.linear_axis(np.asarray(moments, dtype=float))
    if axis is not None:
        omega[axis] = 0.0
    return omega


def assert_matches(got_omega, got_attitude, want_omega, want_attitude, scale, tolerance, what):
    got_omega = np.asarray(got_omega)
    got_attitude = np.asarray(got_attitude)
    assert np.all(np.isfinite(got_omega)) and np.all(np.isfinite(got_attitude)), f"NaN/inf: {what}"
    omega_error = np.abs(got_omega - want_omega).max() / scale if scale > 0 else \
        np.abs(got_omega - want_omega).max()
    attitude_error = np.abs(got_attitude - want_attitude).max()
    assert omega_error <= tolerance, f"omega error {omega_error:.3g} > {tolerance:g}: {what}"
    assert attitude_error <= tolerance, f"attitude error {attitude_error:.3g} > {tolerance:g}: {what}"


def assert_matches_reference(rotor, moments, omega, attitude, times,
                             tolerance=REFERENCE_TOLERANCE):
    times = np.asarray(times, dtype=float)
    got_omega, got_attitude = rotor.evolve(times)
    want_omega, want_attitude = reference.integrate(moments, omega, attitude, times)
    scale = np.linalg.norm(effective_omega(moments, omega))
    assert_matches(got_omega, got_attitude, want_omega, want_attitude, scale, tolerance,
                   describe(moments, omega, attitude, times))


def assert_physical(moments, omega, attitude, omegas, attitudes, what=""):
    """Finite, orthonormal, proper, and energy, |L| and lab-frame L conserved."""
    moments = np.asarray(moments, dtype=float)
    omega = effective_omega(moments, omega)
    omegas = np.asarray(omegas).reshape(-1, 3)
    attitudes = np.asarray(attitudes).reshape(-1, 3, 3)
    what = what or describe(moments, omega, attitude)
    assert np.all(np.isfinite(omegas)) and np.all(np.isfinite(attitudes)), f"NaN/inf: {what}"
    orthonormality = np.abs(attitudes @ attitudes.transpose(0, 2, 1) - np.eye(3)).max()
    assert orthonormality <= ORTHONORMAL_TOLERANCE, f"|A A^T - 1| = {orthonormality:.3g}: {what}"
    determinant = np.abs(np.linalg.det(attitudes) - 1).max()
    assert determinant <= ORTHONORMAL_TOLERANCE, f"|det A - 1| = {determinant:.3g}: {what}"
    energy0 = np.sum(moments * omega**2)
    momentum0 = np.linalg.norm(moments * omega)
    energies = np.sum(moments * omegas**2, axis=1)
    momenta = np.linalg.norm(moments * omegas, axis=1)
    if energy0 == 0:
        assert np.all(energies == 0), f"energy appeared from nothing: {what}"
        return
    energy_drift = np.abs(energies / energy0 - 1).max()
    momentum_drift = np.abs(momenta / momentum0 - 1).max()
    assert energy_drift <= CONSERVATION_TOLERANCE, f"energy drift {energy_drift:.3g}: {what}"
    assert momentum_drift <= CONSERVATION_TOLERANCE, f"|L| drift {momentum_drift:.3g}: {what}"
    lab0 = attitude.T @ (moments * omega)
    labs = np.einsum("nji,nj->ni", attitudes, moments * omegas)
    lab_drift = np.abs(labs - lab0).max() / momentum0
    assert lab_drift <= LAB_MOMENTUM_TOLERANCE, f"lab-frame L drift {lab_drift:.3g}: {what}"


def check_parameter(rotor, moments, omega):
    """parameter in [0, 1] and equal to the exact m of the given (binary) input."""
    m = rotor.parameter
    assert 0.0 <= m <= 1.0, f"parameter {m!r} outside [0, 1]: {describe(moments, omega)}"
    exact = float(reference.exact_parameter(moments, omega))
    assert abs(m - exact) <= 1e-14, \
        f"parameter {m!r}, exact {exact!r}: {describe(moments, omega)}"


def random_body(rng, order, magnitude=None):
    """Distinct moments in [0.2, 5] arranged by `order`, random omega and attitude."""
    while True:
        sorted_moments = np.sort(np.exp(rng.uniform(np.log(0.2), np.log(5.0), 3)))
        if np.diff(sorted_moments).min() > 0.02 * sorted_moments[-1]:
            break
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    if magnitude is None:
        magnitude = np.exp(rng.uniform(np.log(0.1), np.log(10.0)))
    return arrange(sorted_moments, order), direction * magnitude, reference.random_rotation(rng)


# ============================================================================================
# The paper's Section 5 example

@pytest.mark.parametrize("t", [1.0, 10.0])
def test_paper_example(t):
    rotor = FreeRotor(PAPER_MOMENTS, PAPER_OMEGA, PAPER_ATTITUDE)
    omega, attitude = rotor.evolve(t)
    scale = np.linalg.norm(PAPER_OMEGA)
    assert_matches(omega, attitude, *PAPER_VALUES[t], scale, 1e-11, f"paper example, t={t}")
    assert_matches(omega, attitude, *PRECISE_VALUES[t], scale, 1e-12,
                   f"paper example (30-digit values), t={t}")


def test_paper_example_properties():
    rotor = FreeRotor(PAPER_MOMENTS, PAPER_OMEGA)
    assert rotor.kind == "asymmetric"
    assert rotor.representation in ASYMMETRIC
    assert rotor.energy == pytest.approx(0.5 * (10 + 20 * 225 + 26), rel=1e-15)
    np.testing.assert_allclose(rotor.angularMomentum, [10.0, 300.0, 26.0], rtol=1e-15)
    np.testing.assert_array_equal(rotor.moments, PAPER_MOMENTS)
    np.testing.assert_array_equal(rotor.omega, PAPER_OMEGA)
    np.testing.assert_array_equal(rotor.attitude, np.eye(3))
    check_parameter(rotor, PAPER_MOMENTS, PAPER_OMEGA)


# ============================================================================================
# Random asymmetric bodies: every ordering of the moments, random attitude and omega

RANDOM_BODY_COUNT = 300
_random_rng = np.random.default_rng(20070145)
RANDOM_BODIES = [random_body(_random_rng, SLOT_ORDERS[i % 6]) for i in range(RANDOM_BODY_COUNT)]
RANDOM_TIMES = np.array([0.013, 0.37, 1.0, 1.71, 3.3])  # in rotation periods 2 pi / |omega|


@pytest.mark.parametrize("index", range(RANDOM_BODY_COUNT))
def test_random_body_matches_reference(index):
    moments, omega, attitude = RANDOM_BODIES[index]
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == "asymmetric"
    assert rotor.representation in ASYMMETRIC
    check_parameter(rotor, moments, omega)
    times = RANDOM_TIMES * rotation_period(omega)
    assert_matches_reference(rotor, moments, omega, attitude, times)
    # t = 0 gives back the initial state
    omega0, attitude0 = rotor.evolve(0.0)
    assert_matches(omega0, attitude0, omega, attitude, np.linalg.norm(omega), 1e-14,
                   "t = 0: " + describe(moments, omega, attitude))


@pytest.mark.parametrize("index", range(0, RANDOM_BODY_COUNT, 3))
def test_random_body_conserves_invariants(index):
    moments, omega, attitude = RANDOM_BODIES[index]
    rotor = FreeRotor(moments, omega, attitude)
    times = np.concatenate([RANDOM_TIMES, [-2.5, 17.3, 99.9]]) * rotation_period(omega)
    omegas, attitudes = rotor.evolve(times)
    assert_physical(moments, omega, attitude, omegas, attitudes)
    assert rotor.energy == pytest.approx(0.5 * np.sum(moments * omega**2), rel=1e-15)
    np.testing.assert_allclose(rotor.angularMomentum, moments * omega, rtol=1e-15)


@pytest.mark.parametrize("index", range(1, RANDOM_BODY_COUNT, 25))
def test_negative_times(index):
    moments, omega, attitude = RANDOM_BODIES[index]
    rotor = FreeRotor(moments, omega, attitude)
    times = -RANDOM_TIMES * rotation_period(omega)
    assert_matches_reference(rotor, moments, omega, attitude, times)
    # forward then backward returns to the start
    omega1, attitude1 = rotor.evolve(-times[-1])
    back_omega, back_attitude = FreeRotor(moments, omega1, attitude1).evolve(times[-1])
    assert_matches(back_omega, back_attitude, omega, attitude, np.linalg.norm(omega), 1e-12,
                   describe(moments, omega, attitude))


# ============================================================================================
# The separatrix E = L^2 / (2 I2) (m = 1) and its neighbourhood

def separatrix_times(moments, omega, growth_rates=(0.5, 2.0, 5.0, 8.0, -5.0)):
    return np.array(growth_rates) / reference.separatrix_growth_rate(moments, omega)


# Exactly on the separatrix in binary: I1 w1^2 (I1 - I2) + I3 w3^2 (I3 - I2) = 0 in integers.
EXACT_SEPARATRIX = [
    ((2.0, 3.0, 6.0), (3.0, w2, 1.0)) for w2 in (0.0, 2.0, -5.0)
] + [
    ((1.0, 5.0, 9.0), (3.0, w2, 1.0)) for w2 in (0.0, 0.5, -7.0)
] + [
    ((2.0**-20, 3 * 2.0**-20, 6 * 2.0**-20), (3 * 2.0**30, 2.0**31, 2.0**30)),
]


@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("body", EXACT_SEPARATRIX, ids=str)
def test_exact_separatrix(body, order):
    moments = arrange(body[0], order)
    omega = arrange(body[1], order)
    assert reference.separatrix_offset(moments, omega) == 0.0
    attitude = reference.random_rotation(np.random.default_rng(SLOT_ORDERS.index(order)))
    rotor = FreeRotor(moments, omega, attitude)
    what = describe(moments, omega, attitude)
    assert rotor.kind == "asymmetric"
    assert rotor.parameter == 1.0, f"parameter {rotor.parameter!r}: {what}"
    assert rotor.representation == "elliptic-integral", what
    assert_matches_reference(rotor, moments, omega, attitude, separatrix_times(moments, omega))
    with pytest.raises(openmm.OpenMMException, match=r"(?i)separatrix|m = 1|theta"):
        FreeRotor(moments, omega, attitude, representation="theta-series")


@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("body", EXACT_SEPARATRIX[1:6:3], ids=str)
def test_exact_separatrix_approaches_middle_axis(body, order):
    """On the separatrix the body tends to steady rotation about the middle axis as t -> +-inf."""
    moments = arrange(body[0], order)
    omega = arrange(body[1], order)
    attitude = reference.random_rotation(np.random.default_rng(3))
    rotor = FreeRotor(moments, omega, attitude)
    middle = order.index(1)
    limit = np.linalg.norm(moments * omega) / moments[middle]
    times = np.array([-60.0, -40.0, 40.0, 60.0, 400.0]) / \
        reference.separatrix_growth_rate(moments, omega)
    omegas, attitudes = rotor.evolve(times)
    what = describe(moments, omega, attitude)
    assert_physical(moments, omega, attitude, omegas, attitudes, what)
    others = np.delete(omegas, middle, axis=1)
    assert np.abs(others).max() <= 1e-10 * limit, f"{omegas.tolist()}: {what}"
    assert np.abs(np.abs(omegas[:, middle]) - limit).max() <= 1e-13 * limit, what


NEAR_SEPARATRIX_OFFSETS = [0.0, 1e-6, -1e-6, 1e-10, -1e-10, 1e-14, -1e-14]


@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("offset", NEAR_SEPARATRIX_OFFSETS, ids=lambda x: f"offset={x:g}")
def test_near_separatrix(offset, order):
    """(L^2 - 2E I2)/L^2 = offset: 0 (to the last bit, analytically), then 1e-6 ... 1e-14 on
    both sides (offset > 0: E below the separatrix, omega circling the largest moment's axis;
    offset < 0: above it, circling the smallest moment's axis)."""
    rng = np.random.default_rng(1000 + SLOT_ORDERS.index(order))
    moments, omega, attitude = random_body(rng, order)
    omega = reference.near_separatrix_omega(moments, omega, offset)
    assert abs(reference.separatrix_offset(moments, omega) - offset) <= 1e-15 + 1e-3 * abs(offset)
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == "asymmetric"
    assert rotor.representation in ASYMMETRIC
    check_parameter(rotor, moments, omega)
    assert_matches_reference(rotor, moments, omega, attitude, separatrix_times(moments, omega))
    # several passes near the unstable axis: still a rotation, still conserving
    times = np.array([0.5, 3.0, 10.0, 30.0, -20.0]) * rotation_period(omega)
    assert_physical(moments, omega, attitude, *rotor.evolve(times))


# ============================================================================================
# Steady rotation about a principal axis; omega with a zero component; omega = 0

@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_steady_rotation_about_principal_axis(order, axis, sign):
    """omega along a principal axis stays there (the middle axis too: unstable, but exact)."""
    rng = np.random.default_rng(50 + axis)
    moments, _, attitude = random_body(rng, order)
    omega = np.zeros(3)
    omega[axis] = sign * 1.7
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == "asymmetric"
    assert 0.0 <= rotor.parameter <= 1.0
    times = np.array([0.1, 1.0, 2.6, -1.3]) * rotation_period(omega)
    omegas, attitudes = rotor.evolve(times)
    what = describe(moments, omega, attitude)
    for k, t in enumerate(times):
        assert_matches(omegas[k], attitudes[k], omega,
                       reference.steady_rotation(omega, attitude, t), 1.7, 1e-12, what)
    assert_physical(moments, omega, attitude, omegas, attitudes, what)


@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_almost_steady_rotation(order, axis):
    """omega within 1e-12 of a principal axis (for the middle axis: limited to lambda t <= 8)."""
    rng = np.random.default_rng(60 + axis)
    moments, _, attitude = random_body(rng, order)
    omega = rng.normal(size=3) * 1e-12
    omega[axis] = 1.3
    rotor = FreeRotor(moments, omega, attitude)
    check_parameter(rotor, moments, omega)
    times = np.array([0.1, 1.0, 2.6, -1.3]) * rotation_period(omega)
    if order[axis] == 1:
        times = separatrix_times(moments, omega)
    assert_matches_reference(rotor, moments, omega, attitude, times)
    assert_physical(moments, omega, attitude, *rotor.evolve(times))


@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("zero", [0, 1, 2])
def test_one_zero_component_of_omega(order, zero):
    rng = np.random.default_rng(70 + zero)
    moments, omega, attitude = random_body(rng, order)
    omega[zero] = 0.0
    rotor = FreeRotor(moments, omega, attitude)
    check_parameter(rotor, moments, omega)
    times = RANDOM_TIMES * rotation_period(omega)
    assert_matches_reference(rotor, moments, omega, attitude, times)
    assert_physical(moments, omega, attitude, *rotor.evolve(times))


ZERO_OMEGA_BODIES = {
    "asymmetric": (1.0, 2.0, 3.0),
    "symmetric": (2.0, 1.0, 2.0),
    "spherical": (1.5, 1.5, 1.5),
    "linear": (1.5, 1.5, 0.0),
}


@pytest.mark.parametrize("kind", sorted(ZERO_OMEGA_BODIES))
def test_zero_omega(kind):
    moments = ZERO_OMEGA_BODIES[kind]
    attitude = reference.random_rotation(np.random.default_rng(9))
    rotor = FreeRotor(moments, [0.0, 0.0, 0.0], attitude)
    assert rotor.kind == kind
    assert rotor.energy == 0.0
    assert 0.0 <= rotor.parameter <= 1.0
    np.testing.assert_array_equal(rotor.angularMomentum, np.zeros(3))
    omegas, attitudes = rotor.evolve(np.array([0.0, 1.0, -3.0, 1e6]))
    assert np.all(omegas == 0.0)
    assert np.abs(attitudes - attitude).max() <= 1e-15


def test_linear_rotor_spinning_only_about_its_axis_is_at_rest():
    attitude = reference.random_rotation(np.random.default_rng(10))
    rotor = FreeRotor([0.0, 2.0, 2.0], [5.0, 0.0, 0.0], attitude)
    assert rotor.kind == "linear"
    assert rotor.energy == 0.0
    omegas, attitudes = rotor.evolve(np.array([1.0, 100.0]))
    assert np.all(omegas == 0.0)
    assert np.abs(attitudes - attitude).max() <= 1e-15


# ============================================================================================
# Exact and nearly degenerate moments

@pytest.mark.parametrize("moment", [1.0, 2.5e-3, 7.0e4])
def test_spherical_top(moment):
    rng = np.random.default_rng(int(np.log(moment) * 100) % 1000)
    omega = rng.normal(size=3)
    attitude = reference.random_rotation(rng)
    moments = (moment, moment, moment)
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == "spherical"
    assert rotor.representation == "closed-form"
    times = np.array([0.1, 1.0, 2.6, -1.3]) * rotation_period(omega)
    omegas, attitudes = rotor.evolve(times)
    for k, t in enumerate(times):
        assert_matches(omegas[k], attitudes[k], omega,
                       reference.steady_rotation(omega, attitude, t),
                       np.linalg.norm(omega), 1e-12, describe(moments, omega, attitude, t))
    assert_matches_reference(rotor, moments, omega, attitude, times)
    assert_physical(moments, omega, attitude, omegas, attitudes)


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("shape", ["oblate", "prolate"])
@pytest.mark.parametrize("spin", ["generic", "along-axis", "perpendicular"])
def test_symmetric_top(axis, shape, spin):
    rng = np.random.default_rng(20 + axis)
    moments = np.full(3, 1.3)
    moments[axis] = 2.1 if shape == "oblate" else 0.45
    omega = rng.normal(size=3)
    if spin == "along-axis":
        omega[[k for k in range(3) if k != axis]] = 0.0
    elif spin == "perpendicular":
        omega[axis] = 0.0
    attitude = reference.random_rotation(rng)
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == "symmetric"
    assert rotor.representation == "closed-form"
    times = np.array([0.1, 1.0, 2.6, -1.3]) * rotation_period(omega)
    omegas, attitudes = rotor.evolve(times)
    for k, t in enumerate(times):
        want_omega, want_attitude = reference.symmetric_top(moments, omega, attitude, t, axis)
        assert_matches(omegas[k], attitudes[k], want_omega, want_attitude,
                       np.linalg.norm(omega), 1e-12, describe(moments, omega, attitude, t))
    assert_matches_reference(rotor, moments, omega, attitude, times)
    assert_physical(moments, omega, attitude, omegas, attitudes)


NEARLY_DEGENERATE = {
    # sorted moments: equal to 1e-9 relative
    "near-spherical": (1.0, 1.0 + 1e-9, 1.0 + 2.3e-9),
    "near-oblate": (1.0, 1.0 + 1e-9, 1.9),     # the two small moments nearly equal
    "near-prolate": (0.6, 1.4, 1.4 * (1 + 1e-9)),  # the two large moments nearly equal
}


@pytest.mark.parametrize("order", SLOT_ORDERS, ids=str)
@pytest.mark.parametrize("body", sorted(NEARLY_DEGENERATE))
def test_nearly_degenerate_moments(body, order):
    rng = np.random.default_rng(30 + SLOT_ORDERS.index(order))
    moments = arrange(NEARLY_DEGENERATE[body], order)
    _, omega, attitude = random_body(rng, order)
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == "asymmetric"
    assert rotor.representation in ASYMMETRIC
    check_parameter(rotor, moments, omega)
    times = RANDOM_TIMES * rotation_period(omega)
    assert_matches_reference(rotor, moments, omega, attitude, times)
    assert_physical(moments, omega, attitude, *rotor.evolve(times))


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_linear_rotor(axis):
    rng = np.random.default_rng(40 + axis)
    moments = np.full(3, 1.7)
    moments[axis] = 0.0
    omega = rng.normal(size=3)
    perpendicular = omega.copy()
    perpendicular[axis] = 0.0
    attitude = reference.random_rotation(rng)
    rotor = FreeRotor(moments, omega, attitude)
    plain = FreeRotor(moments, perpendicular, attitude)
    what = describe(moments, omega, attitude)
    assert rotor.kind == "linear"
    assert rotor.representation == "closed-form"
    np.testing.assert_array_equal(rotor.omega, perpendicular)
    assert rotor.energy == pytest.approx(0.5 * 1.7 * np.sum(perpendicular**2), rel=1e-15)
    np.testing.assert_allclose(rotor.angularMomentum, moments * perpendicular, rtol=1e-15,
                               atol=0)
    times = np.array([0.1, 1.0, 2.6, -1.3]) * rotation_period(perpendicular)
    omegas, attitudes = rotor.evolve(times)
    plain_omegas, plain_attitudes = plain.evolve(times)
    # the axial component has no effect at all
    assert_matches(omegas, attitudes, plain_omegas, plain_attitudes,
                   np.linalg.norm(perpendicular), 1e-15, what)
    for k, t in enumerate(times):
        assert_matches(omegas[k], attitudes[k], perpendicular,
                       reference.steady_rotation(perpendicular, attitude, t),
                       np.linalg.norm(perpendicular), 1e-12, what)
    # the reference drops the axial component and the axial Euler equation
    assert_matches_reference(rotor, moments, omega, attitude, times)
    assert_physical(moments, omega, attitude, omegas, attitudes, what)


# ============================================================================================
# Scale covariance: |omega| from 1e-8 to 1e8 (the unit of the moments: TestFreeRotor.cpp, testScaling)

SCALE_BODIES = {
    "generic": ((0.7, 1.9, 1.2), (0.4, -0.9, 0.6)),
    "near-separatrix": ((0.7, 1.9, 1.2), tuple(reference.near_separatrix_omega(
        (0.7, 1.9, 1.2), (0.4, -0.9, 0.6), 1e-6))),
}


@pytest.mark.parametrize("scale", [1e-8, 1e-4, 1e4, 1e8, 2.0**-26, 2.0**26])
@pytest.mark.parametrize("body", sorted(SCALE_BODIES))
def test_omega_scale_covariance(body, scale):
    """Rotor with omega scaled by s, evolved to t/s, equals the unscaled one evolved to t."""
    moments, omega = (np.array(x) for x in SCALE_BODIES[body])
    attitude = reference.random_rotation(np.random.default_rng(12))
    times = separatrix_times(moments, omega) if body == "near-separatrix" else \
        np.array([0.37, 2.9, -1.1]) * rotation_period(omega)
    unscaled_omega, unscaled_attitude = FreeRotor(moments, omega, attitude).evolve(times)
    scaled = FreeRotor(moments, omega * scale, attitude)
    scaled_omega, scaled_attitude = scaled.evolve(times / scale)
    exact = np.log2(scale) == int(np.log2(scale))  # powers of two scale without rounding
    assert_matches(scaled_omega / scale, scaled_attitude, unscaled_omega, unscaled_attitude,
                   np.linalg.norm(omega), 1e-14 if exact else 1e-12,
                   f"scale {scale}: " + describe(moments, omega * scale, attitude, times / scale))
    assert_matches_reference(scaled, moments, omega * scale, attitude, times / scale)


# ============================================================================================
# The two representations of an asymmetric top agree (m in [0.3, 0.99])

def omega_for_parameter(moments, omega, m, side):
    """omega with one component changed so that the elliptic parameter is m.

    side "low": E < L^2/(2 I2), the internal ordering (eq. 3.32) has I1 = the smallest moment and
    the largest moment's component is solved for; "high": E > L^2/(2 I2), I1 = the largest and
    the smallest moment's component is solved for. None when m is out of reach.
    """
    moments = np.asarray(moments, dtype=float)
    omega = np.array(omega, dtype=float)
    first, middle, third = np.argsort(moments)
    if side == "high":
        first, third = third, first
    i1, i2, i3 = moments[[first, middle, third]]
    w1, w2, w3 = omega[[first, middle, third]]
    d3 = i1 * w1**2 * (i1 - i3) + i2 * w2**2 * (i2 - i3)   # L^2 - 2E I3, free of w3
    d1 = d3 * (i1 - i2) / (m * (i3 - i2))                   # L^2 - 2E I1 that gives m
    w3_squared = (d1 - i2 * w2**2 * (i2 - i1)) / (i3 * (i3 - i1))
    if not w3_squared > 0:
        return None
    omega[third] = np.copysign(np.sqrt(w3_squared), w3)
    return omega


PARAMETER_TARGETS = [0.3, 0.5, 0.7, 0.9, 0.97, 0.99]


@pytest.mark.parametrize("order", SLOT_ORDERS[::2], ids=str)
@pytest.mark.parametrize("side", ["low", "high"])
@pytest.mark.parametrize("target", PARAMETER_TARGETS)
def test_representations_agree(target, side, order):
    rng = np.random.default_rng(int(target * 100) + 7 * SLOT_ORDERS.index(order))
    while True:
        moments, omega, attitude = random_body(rng, order)
        omega = omega_for_parameter(moments, omega, target, side)
        if omega is not None:
            break
    assert abs(float(reference.exact_parameter(moments, omega)) - target) <= 1e-12
    assert (reference.separatrix_offset(moments, omega) > 0) == (side == "low")
    what = describe(moments, omega, attitude)
    rotors = {name: FreeRotor(moments, omega, attitude, representation=name)
              for name in ASYMMETRIC}
    times = np.array([0.2, 1.0, 2.7, -1.4]) * rotation_period(omega)
    results = {}
    for name, rotor in rotors.items():
        assert rotor.representation == name, what
        assert rotor.kind == "asymmetric"
        check_parameter(rotor, moments, omega)
        assert_matches_reference(rotor, moments, omega, attitude, times)
        results[name] = rotor.evolve(times)
        assert_physical(moments, omega, attitude, *results[name], what)
    assert_matches(*results["theta-series"], *results["elliptic-integral"],
                   np.linalg.norm(omega), 1e-12, "theta-series vs elliptic-integral: " + what)
    automatic = FreeRotor(moments, omega, attitude)
    assert automatic.representation in ASYMMETRIC
    assert_matches(*automatic.evolve(times), *results[automatic.representation],
                   np.linalg.norm(omega), 1e-15, "auto vs forced: " + what)


# ============================================================================================
# Long times: the flow property, and omega against the 40-digit closed form

LONG_TIME_BODIES = {
    "generic": ((1.1, 2.9, 1.7), (0.3, -0.8, 1.1)),
    # (L^2 - 2E I2)/L^2 = 1e-3, m ~ 0.996: an ulp of the restarted state moves omega(1e4
    # periods) by ~6e-11 here (1e-9 budget); at 1e-4 it is already ~1e-9, so that is the limit
    # of what double precision can check this way.
    "near-separatrix": ((1.1, 2.9, 1.7), tuple(reference.near_separatrix_omega(
        (1.1, 2.9, 1.7), (0.3, -0.8, 1.1), 1e-3))),
}


@pytest.mark.parametrize("split", [0.5 / 1e4, 1 / 3, 0.9999])
@pytest.mark.parametrize("body", sorted(LONG_TIME_BODIES))
def test_flow_property_long_times(body, split):
    """evolve(t1 + t2) = FreeRotor(state at t1).evolve(t2), t1 + t2 = 1e4 rotation periods."""
    moments, omega = (np.array(x) for x in LONG_TIME_BODIES[body])
    attitude = reference.random_rotation(np.random.default_rng(14))
    total = 1e4 * rotation_period(omega)
    t1 = split * total
    t2 = total - t1
    rotor = FreeRotor(moments, omega, attitude)
    direct_omega, direct_attitude = rotor.evolve(t1 + t2)
    omega1, attitude1 = rotor.evolve(t1)
    restarted = FreeRotor(moments, omega1, attitude1)
    two_step_omega, two_step_attitude = restarted.evolve(t2)
    what = f"t1={t1!r}, t2={t2!r}: " + describe(moments, omega, attitude)
    assert_matches(two_step_omega, two_step_attitude, direct_omega, direct_attitude,
                   np.linalg.norm(omega), 1e-9, what)
    assert_physical(moments, omega, attitude, [direct_omega, two_step_omega],
                    [direct_attitude, two_step_attitude], what)


@pytest.mark.parametrize("periods", [10.0, 1e3, 1e4])
@pytest.mark.parametrize("body", sorted(LONG_TIME_BODIES))
def test_long_time_omega_against_closed_form(body, periods):
    moments, omega = (np.array(x) for x in LONG_TIME_BODIES[body])
    t = periods * rotation_period(omega)
    got, _ = FreeRotor(moments, omega).evolve(t)
    want = reference.omega_closed_form(moments, omega, t)
    error = np.abs(got - want).max() / np.linalg.norm(omega)
    assert error <= 1e-9, f"error {error:.3g}, t={t!r}: " + describe(moments, omega)


# ============================================================================================
# Vectorized evolve

VECTOR_BODIES = {
    "asymmetric": ((1.0, 2.0, 3.5), (0.3, 1.1, -0.4)),
    "separatrix": ((2.0, 3.0, 6.0), (3.0, 2.0, 1.0)),
    "symmetric": ((2.0, 1.0, 2.0), (0.3, 1.1, -0.4)),
    "spherical": ((1.5, 1.5, 1.5), (0.3, 1.1, -0.4)),
    "linear": ((0.0, 1.5, 1.5), (0.3, 1.1, -0.4)),
}


@pytest.mark.parametrize("body", sorted(VECTOR_BODIES))
def test_vectorized_evolve_equals_scalar_calls(body):
    moments, omega = VECTOR_BODIES[body]
    attitude = reference.random_rotation(np.random.default_rng(15))
    rotor = FreeRotor(moments, omega, attitude)
    times = np.array([0.0, 0.25, -3.0, 7.5, 100.0, 0.25])
    omegas, attitudes = rotor.evolve(times)
    assert omegas.shape == (6, 3) and attitudes.shape == (6, 3, 3)
    for k, t in enumerate(times):
        one_omega, one_attitude = rotor.evolve(float(t))
        assert one_omega.shape == (3,) and one_attitude.shape == (3, 3)
        assert_matches(omegas[k], attitudes[k], one_omega, one_attitude,
                       np.linalg.norm(omega), 1e-15, f"t={t}: " + describe(moments, omega))
    for t in (np.float64(0.25), 0.25, np.array(0.25)):
        one_omega, one_attitude = rotor.evolve(t)
        assert one_omega.shape == (3,) and one_attitude.shape == (3, 3)
        np.testing.assert_array_equal(one_omega, omegas[1])
        np.testing.assert_array_equal(one_attitude, attitudes[1])
    np.testing.assert_array_equal(rotor.evolve(2)[0], rotor.evolve(2.0)[0])
    for n in (0, 1):
        many_omega, many_attitude = rotor.evolve(times[:n])
        assert many_omega.shape == (n, 3) and many_attitude.shape == (n, 3, 3)
    listed_omega, _ = rotor.evolve(list(times))
    np.testing.assert_array_equal(listed_omega, omegas)


# ============================================================================================
# Properties

def test_properties_report_the_input():
    rng = np.random.default_rng(16)
    moments, omega, attitude = random_body(rng, (2, 0, 1))
    rotor = FreeRotor(list(moments), tuple(omega), attitude)
    np.testing.assert_array_equal(rotor.moments, moments)
    np.testing.assert_array_equal(rotor.omega, omega)
    np.testing.assert_array_equal(rotor.attitude, attitude)
    assert rotor.moments.shape == (3,) and rotor.attitude.shape == (3, 3)
    np.testing.assert_array_equal(FreeRotor(moments, omega).attitude, np.eye(3))


@pytest.mark.parametrize("moments, kind", [
    ((1.0, 2.0, 3.0), "asymmetric"),
    ((3.0, 1.0, 2.0), "asymmetric"),
    ((2.0, 2.0, 2.0), "spherical"),
    ((1.0, 1.0, 2.0), "symmetric"),
    ((1.0, 2.0, 1.0), "symmetric"),
    ((2.0, 1.0, 1.0), "symmetric"),
    ((2.0, 2.0, 1.0), "symmetric"),
    ((0.0, 1.0, 1.0), "linear"),
    ((1.0, 0.0, 1.0), "linear"),
    ((1.0, 1.0, 0.0), "linear"),
])
def test_kind(moments, kind):
    rotor = FreeRotor(moments, (0.3, 0.2, 0.1))
    assert rotor.kind == kind
    if kind == "asymmetric":
        assert rotor.representation in ASYMMETRIC
    else:
        assert rotor.representation == "closed-form"


@pytest.mark.parametrize("moments, kind, equal", [
    ((2.0, 2.0 * (1 + 5e-14), 3.0), "symmetric", (0, 1)),        # within 1e-13 of the largest
    ((3.0, 1.0 * (1 - 2e-14), 1.0), "symmetric", (1, 2)),
    ((2.0, 2.0 * (1 + 4e-14), 2.0 * (1 - 4e-14)), "spherical", (0, 1, 2)),
    ((1e-14, 2.0, 2.0 * (1 + 3e-14)), "linear", (1, 2)),         # a moment below 1e-13 of the largest is zero
    ((10.0, 10.0 * (1 + 1e-12), 26.0), "asymmetric", ()),        # 1e-12 apart: a genuine asymmetric top
])
def test_classification_snaps_moments_within_tolerance(moments, kind, equal):
    """One classification with one tolerance (1e-13 of the largest moment): moments it finds equal
    (or zero) are made exactly so, and the motion is the exact motion of those moments; against the
    independent reference it matches the given moments within the usual tolerance."""
    rng = np.random.default_rng(61)
    omega = rng.normal(size=3)
    attitude = reference.random_rotation(rng)
    rotor = FreeRotor(moments, omega, attitude)
    assert rotor.kind == kind
    used = rotor.moments
    assert np.all(np.abs(used - np.asarray(moments)) <= 1e-13 * max(moments))
    for i, j in itertools.combinations(equal, 2):
        assert used[i] == used[j]
    if kind == "linear":
        assert used[0] == 0.0
    exact = FreeRotor(used, omega, attitude)
    times = np.array([0.1, 1.0, 2.6, -1.3]) * rotation_period(omega)
    got, want = rotor.evolve(times), exact.evolve(times)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    if kind != "linear":
        assert_matches_reference(rotor, np.asarray(moments), omega, attitude, times)


# ============================================================================================
# Bad input: openmm.OpenMMException with a message naming the problem

def both(first, second):
    """A regex matching a message that mentions both alternatives (any order, any case)."""
    return rf"(?is)(?=.*({first}))(?=.*({second}))"


NOT_FINITE = r"finite|nan|inf"
MOMENT = r"moment"
OMEGA = r"omega|angular velocity"
ATTITUDE = r"attitude"
SHAPE = r"shape|size|length|element|component|entries|dimension"

BAD_CONSTRUCTOR_INPUT = [
    # non-positive moments (other than a linear body)
    ("negative moment", ((-1.0, 2.0, 3.0), (1, 1, 1), None), MOMENT),
    ("negative moment, equal others", ((-1.0, 2.0, 2.0), (1, 1, 1), None), MOMENT),
    ("zero moment, unequal others", ((0.0, 2.0, 3.0), (1, 1, 1), None), MOMENT),
    ("zero moment, nearly equal others", ((2.0, 0.0, 2.0 * (1 + 1e-9)), (1, 1, 1), None),
     MOMENT),
    ("two zero moments", ((0.0, 0.0, 3.0), (1, 1, 1), None), MOMENT),
    ("three zero moments", ((0.0, 0.0, 0.0), (1, 1, 1), None), MOMENT),
    # not finite
    ("NaN moment", ((1.0, np.nan, 3.0), (1, 1, 1), None), both(MOMENT, NOT_FINITE)),
    ("infinite moment", ((1.0, 2.0, np.inf), (1, 1, 1), None), both(MOMENT, NOT_FINITE)),
    ("NaN omega", ((1.0, 2.0, 3.0), (np.nan, 1, 1), None), both(OMEGA, NOT_FINITE)),
    ("infinite omega", ((1.0, 2.0, 3.0), (1, -np.inf, 1), None), both(OMEGA, NOT_FINITE)),
    ("NaN omega, linear axis", ((0.0, 2.0, 2.0), (np.nan, 1, 1), None),
     both(OMEGA, NOT_FINITE)),
    ("NaN attitude", ((1.0, 2.0, 3.0), (1, 1, 1), np.where(np.eye(3) > 0, 1.0, np.nan)),
     both(ATTITUDE, NOT_FINITE)),
    ("infinite attitude", ((1.0, 2.0, 3.0), (1, 1, 1), np.diag([1.0, np.inf, 1.0])),
     both(ATTITUDE, NOT_FINITE)),
    # not a rotation
    ("scaled attitude", ((1.0, 2.0, 3.0), (1, 1, 1), 1.001 * np.eye(3)),
     both(ATTITUDE, r"orthonormal|orthogonal|rotation")),
    ("sheared attitude", ((1.0, 2.0, 3.0), (1, 1, 1), np.array(
        [[1.0, 1e-3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])),
     both(ATTITUDE, r"orthonormal|orthogonal|rotation")),
    ("zero attitude", ((1.0, 2.0, 3.0), (1, 1, 1), np.zeros((3, 3))),
     both(ATTITUDE, r"orthonormal|orthogonal|rotation")),
    ("inversion", ((1.0, 2.0, 3.0), (1, 1, 1), -np.eye(3)),
     both(ATTITUDE, r"determinant|reflection|improper|proper|handed")),
    ("reflection", ((1.0, 2.0, 3.0), (1, 1, 1), np.diag([1.0, 1.0, -1.0])),
     both(ATTITUDE, r"determinant|reflection|improper|proper|handed")),
    ("rotation times reflection", ((1.0, 2.0, 3.0), (1, 1, 1),
                                   reference.random_rotation(np.random.default_rng(17))
                                   @ np.diag([1.0, -1.0, 1.0])),
     both(ATTITUDE, r"determinant|reflection|improper|proper|handed")),
    # shapes
    ("two moments", ((1.0, 2.0), (1, 1, 1), None), both(MOMENT, SHAPE)),
    ("four moments", ((1.0, 2.0, 3.0, 4.0), (1, 1, 1), None), both(MOMENT, SHAPE)),
    ("scalar moment", (2.0, (1, 1, 1), None), both(MOMENT, SHAPE)),
    ("two omega components", ((1.0, 2.0, 3.0), (1, 1), None), both(OMEGA, SHAPE)),
    ("omega (3, 3)", ((1.0, 2.0, 3.0), np.eye(3), None), both(OMEGA, SHAPE)),
    ("attitude (3,)", ((1.0, 2.0, 3.0), (1, 1, 1), np.ones(3)), both(ATTITUDE, SHAPE)),
    ("attitude (2, 2)", ((1.0, 2.0, 3.0), (1, 1, 1), np.eye(2)), both(ATTITUDE, SHAPE)),
    ("attitude (3, 4)", ((1.0, 2.0, 3.0), (1, 1, 1), np.eye(3, 4)), both(ATTITUDE, SHAPE)),
    ("attitude (4, 4)", ((1.0, 2.0, 3.0), (1, 1, 1), np.eye(4)), both(ATTITUDE, SHAPE)),
]


@pytest.mark.parametrize("arguments, pattern",
                         [case[1:] for case in BAD_CONSTRUCTOR_INPUT],
                         ids=[case[0] for case in BAD_CONSTRUCTOR_INPUT])
def test_bad_constructor_input(arguments, pattern):
    moments, omega, attitude = arguments
    with pytest.raises(openmm.OpenMMException, match=pattern):
        FreeRotor(moments, omega, attitude)


def test_unequal_linear_moments_message_tells_them_apart():
    """A linear rotor needs its two non-zero moments equal; moments that differ only past the sixth
    digit are printed in full, so that the message shows the difference."""
    with pytest.raises(openmm.OpenMMException, match=r"got 1\.0000001\d* and 1\b"):
        FreeRotor((0.0, 1.0000001, 1.0), (1, 1, 1))


@pytest.mark.parametrize("representation", ["bogus", "", "theta", "Theta-Series", None, 1])
def test_unknown_representation(representation):
    with pytest.raises(openmm.OpenMMException, match=r"(?i)representation"):
        FreeRotor((1.0, 2.0, 3.0), (1, 1, 1), representation=representation)


@pytest.mark.parametrize("t", [np.nan, np.inf, -np.inf, np.array([0.0, 1.0, np.nan]),
                               np.array([np.inf])], ids=str)
@pytest.mark.parametrize("body", ["asymmetric", "separatrix", "symmetric", "linear"])
def test_bad_time(body, t):
    moments, omega = VECTOR_BODIES[body]
    rotor = FreeRotor(moments, omega)
    with pytest.raises(openmm.OpenMMException, match=both(r"time|\bt\b", NOT_FINITE)):
        rotor.evolve(t)


@pytest.mark.parametrize("t", [np.zeros((2, 2)), "1.0"], ids=str)
def test_bad_time_shape_or_type(t):
    rotor = FreeRotor((1.0, 2.0, 3.0), (1, 1, 1))
    with pytest.raises(openmm.OpenMMException, match=r"(?i)\bt\b|time"):
        rotor.evolve(t)
