"""Tests of the cost group's studies (benchmarks/studies/): rotation_accuracy's reference steppers against the exact
rotor and against the C++ integrator, and step_cost's force-free bodies."""

import pathlib
import sys

import numpy as np
import openmm
import pytest

import openmmrigid

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
from studies import rotation_accuracy, step_cost  # noqa: E402
from rigidtesting.bodies import bodyKind  # noqa: E402

TIME = 0.05   # ps


@pytest.fixture(scope="module")
def bodies():
    return rotation_accuracy.randomBodies(12, 3)


def medianError(scheme, bodies, dtFs):
    steps = int(round(TIME/(dtFs*1e-3)))
    moments, attitudes, omegas = bodies
    approximate = rotation_accuracy.integrate(scheme, moments, attitudes, omegas, TIME/steps, steps)
    return np.median(rotation_accuracy.errors(moments, attitudes, omegas, TIME, approximate))


@pytest.mark.parametrize("scheme,order", [("NoSquish", 2), ("first-order", 1)])
def test_reference_steppers_converge_to_the_exact_rotor_at_their_order(bodies, scheme, order):
    """Halving the step divides the attitude error after TIME by 2^order (against openmmrigid.FreeRotor)."""
    coarse, fine = medianError(scheme, bodies, 1.0), medianError(scheme, bodies, 0.5)
    assert 1e-9 < fine < coarse < 0.05
    assert np.log2(coarse/fine) == pytest.approx(order, abs=0.05)


def test_steppers_keep_attitudes_rotations(bodies):
    moments, attitudes, omegas = bodies
    for scheme in rotation_accuracy.STEPPERS:
        result = rotation_accuracy.integrate(scheme, moments, attitudes, omegas, 0.004, 50)
        assert np.allclose(result @ result.transpose(0, 2, 1), np.eye(3), atol=1e-12)
        assert np.allclose(np.linalg.det(result), 1.0)


def test_order_fits_the_slope_below_the_saturation():
    rows = [dict(scheme="s", dt=dt, attitude=[3e-4*dt**2, 0.0]) for dt in (0.25, 0.5, 1, 2, 4)]
    rows += [dict(scheme="s", dt=16, attitude=[1.0, 0.0])]   # saturated: left out of the fit
    assert rotation_accuracy.order(rows, "s") == pytest.approx(2.0, abs=1e-12)


def sixMasses(moments, mass=4.0):
    """Body-frame coordinates of six equal masses at +-x e1, +-y e2, +-z e3 with these principal moments: I1 = 2m(y^2 + z^2)
    and cyclic, so 4 m x^2 = I2 + I3 - I1."""
    half = np.sqrt((moments.sum(axis=1, keepdims=True) - 2*moments)/(4*mass))
    return np.einsum("nk,kj,s->nksj", half, np.eye(3), [1.0, -1.0]).reshape(-1, 6, 3)


def particles(moments, attitudes, omegas):
    """Lab positions r = A^T b and velocities v = (A^T omega) x r of the six masses of each body."""
    r = np.einsum("nji,npj->npi", attitudes, sixMasses(moments))
    return r, np.cross(np.einsum("nji,nj->ni", attitudes, omegas)[:, None, :], r)


@pytest.mark.parametrize("rotation", ["nosquish", "exact"])
def test_the_integrator_follows_the_references_to_rounding(bodies, rotation):
    """RigidBodyIntegrator (Reference platform, no forces) at 2 fs: NoSquish moves as the numpy NO_SQUISH, Exact as
    FreeRotor.evolve, to rounding: the particles' deviation relative to the body's size and speed."""
    moments, attitudes, omegas = bodies
    steps = 25
    system = openmm.System()
    explicit = [[system.addParticle(4.0) for _ in range(6)] for _ in moments]
    integrator = openmmrigid.RigidBodyIntegrator(0.002, explicit)
    integrator.setRotationMethod({"exact": integrator.Exact, "nosquish": integrator.NoSquish}[rotation])
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    x, v = particles(moments, attitudes, omegas)
    context.setPositions(x.reshape(-1, 3))
    context.setVelocities(v.reshape(-1, 3))
    integrator.step(steps)
    state = context.getState(getPositions=True, getVelocities=True)
    if rotation == "exact":
        final = [openmmrigid.FreeRotor(I, w, A).evolve(0.002*steps) for I, w, A in zip(moments, omegas, attitudes)]
        expected = particles(moments, np.array([a for _, a in final]), np.array([w for w, _ in final]))
    else:
        final = rotation_accuracy.integrate("NoSquish", moments, attitudes, omegas, 0.002, steps)
        momentum = np.einsum("nji,nj->ni", attitudes, moments*omegas)
        expected = particles(moments, final, np.einsum("nij,nj->ni", final, momentum)/moments)
    size = np.linalg.norm(sixMasses(moments), axis=2).max(axis=1)[:, None, None]
    got = [q.value_in_unit(q.unit).reshape(-1, 6, 3) for q in (state.getPositions(True), state.getVelocities(True))]
    assert np.abs(got[0] - expected[0]).max(axis=(1, 2)).max() < 1e-10*size.max()
    speed = size[:, 0, 0]*np.linalg.norm(omegas, axis=1)
    assert (np.abs(got[1] - expected[1]).max(axis=(1, 2)) < 1e-10*speed).all()


def test_force_free_bodies_are_the_kinds_the_table_names():
    expected = {"water": "asymmetric", "CO2": "linear", "CH4-like": "spherical", "NH3-like": "symmetric", "Ar": "point"}
    for kind, shape in step_cost.KINDS.items():
        masses, local = shape()[1:3]
        assert bodyKind(masses, local) == expected[kind]
