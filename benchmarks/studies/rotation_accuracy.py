"""Free rotation alone: approximate schemes against the exact rotor of van Zon and Schofield (J. Comput. Phys. 225,
145 (2007); openmmrigid.FreeRotor), used as that paper uses it, as the yardstick; and what the exact one costs."""

import numpy as np, openmmrigid
from harness import Study, pyplot, stamp
from scipy.spatial.transform import Rotation
from rigidtesting import randomRotation
from studies.step_cost import timeBodies

TYPICAL, TARGET = 2.0, 1e-6    # fs where the schemes are compared; rad after T for "the step NO_SQUISH needs"

def randomBodies(count, seed):
    """Moments (ascending, a water's size: I1, I2 in [0.005, 0.02] amu nm^2, I3 in [max(I1, I2), I1 + I2]), lab-to-body
    attitudes (uniform) and body-frame omegas (Boltzmann at 300 K)."""
    rng = np.random.default_rng(seed)
    moments = np.array([sorted([a, b, rng.uniform(max(a, b), a + b)]) for a, b in rng.uniform(0.005, 0.02, (count, 2))])
    attitudes = np.array([randomRotation(rng) for _ in range(count)])
    return moments, attitudes, rng.normal(size=(count, 3))*np.sqrt(0.00831446261815324*300/moments)

def noSquishStep(moments, dt, attitudes, momentum):
    """NO_SQUISH (Miller et al., J. Chem. Phys. 116, 8649 (2002)) as numerics/NoSquish.h does it: rotations about body
    axes 3, 2, 1, 2, 3 (half, half, full, half, half step) of the attitude A and of L_body = A L_lab."""
    body = np.einsum("nij,nj->ni", attitudes, momentum)
    for axis, fraction in ((2, 0.5), (1, 0.5), (0, 1.0), (1, 0.5), (2, 0.5)):
        i, j = (axis + 1) % 3, (axis + 2) % 3
        angle = body[:, axis]/moments[:, axis]*fraction*dt
        c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
        attitudes[:, i], attitudes[:, j] = c*attitudes[:, i] + s*attitudes[:, j], c*attitudes[:, j] - s*attitudes[:, i]
        body[:, [i]], body[:, [j]] = c*body[:, [i]] + s*body[:, [j]], c*body[:, [j]] - s*body[:, [i]]

def firstOrderStep(moments, dt, attitudes, momentum):
    """A <- exp(-dt W(omega_body)) A (W(w) x = w x x; Rodrigues' formula), omega_body = I^-1 A L_lab held over the step."""
    attitudes[:] = Rotation.from_rotvec(-dt*np.einsum("nij,nj->ni", attitudes, momentum)/moments).as_matrix() @ attitudes

STEPPERS = {"NoSquish": noSquishStep, "first-order": firstOrderStep}

def integrate(scheme, moments, attitudes, omegas, dt, steps):
    """The attitudes after `steps` steps (L_lab = A^T I omega, which both schemes conserve exactly, and A move)."""
    attitudes, momentum = attitudes.copy(), np.einsum("nji,nj->ni", attitudes, moments*omegas)
    for _ in range(steps):
        STEPPERS[scheme](moments, dt, attitudes, momentum)
    return attitudes

def errors(moments, attitudes, omegas, t, approximate):
    """Per body, the angle of A A_exact^T, 2 asin(|A - A_exact|_F / 2 sqrt 2), against FreeRotor.evolve(t). As L_lab is
    conserved exactly, every error is in the attitude, and through it in omega_body = I^-1 A L_lab."""
    exact = np.array([openmmrigid.FreeRotor(I, w, A).evolve(t)[1] for I, w, A in zip(moments, omegas, attitudes)])
    return 2*np.arcsin(np.minimum(np.linalg.norm(approximate - exact, axis=(1, 2))/(2*np.sqrt(2)), 1))

def order(rows, scheme):
    """Slope of log(median error) against log(dt) where the median error is below 0.05 rad (then it saturates at pi)."""
    points = np.log([(r["dt"], r["attitude"][0]) for r in rows if r["scheme"] == scheme and r["attitude"][0] < 0.05])
    return float(np.polyfit(*points.T, 1)[0]) if len(points) > 1 else float("nan")

def run(env):
    count, total, rows = 100 if env.quick else 1000, 1.0, []
    moments, attitudes, omegas = randomBodies(count, 2007)
    for scheme, dt in ((s, dt) for s in STEPPERS for dt in 2.0**np.arange(-4 if env.quick else -6, 5)):
        steps = int(round(total/(dt*1e-3)))
        angle = errors(moments, attitudes, omegas, total, integrate(scheme, moments, attitudes, omegas, total/steps, steps))
        rows.append(dict(scheme=scheme, dt=dt, steps=steps, attitude=[np.median(angle), np.percentile(angle, 90)]))
        stamp(f"{scheme} at {dt:g} fs: median attitude error {rows[-1]['attitude'][0]:.3e} rad")
    cost = timeBodies(env, "water", 2000 if env.quick else 8000, env.threads or 1, 0.1 if env.quick else 1.0)
    return dict(bodies=count, time=total, rows=rows, cost=cost)

def report(summary, page):
    rows, cost, T, p = summary["rows"], summary["cost"], summary["time"], order(summary["rows"], "NoSquish")
    at = {r["scheme"]: r["attitude"][0] for r in rows if r["dt"] == TYPICAL}
    ratio = cost["cpu"]["Exact"][0]/cost["cpu"]["NoSquish"][0]
    needed = TYPICAL*(TARGET/at["NoSquish"])**(1/p)    # along the fitted power law
    page.text(f"After {T:g} ps at {TYPICAL:g} fs, median attitude error over {summary['bodies']} bodies: first-order "
              f"{at['first-order']:.2e} rad, NoSquish {at['NoSquish']:.2e} rad. Exact costs **{ratio:.2f}** times NoSquish per "
              f"body and step (CPU time, {cost['bodies']} force-free {cost['kind']} bodies); NoSquish given that time "
              f"({TYPICAL/ratio:.2f} fs) reaches about {at['NoSquish']*ratio**-p:.1e} rad, and {TARGET:g} rad at {needed:.3g} fs: "
              f"**{TYPICAL/needed/ratio:.0f} times** the cost of Exact at {TYPICAL:g} fs.")
    page.table(["scheme", "dt (fs)", "steps", "attitude error (rad): median", "90th percentile"],
               [[r["scheme"], f"{r['dt']:.4g}", r["steps"]] + [f"{v:.3e}" for v in r["attitude"]] for r in rows])
    page.text("; ".join(f"Order of {s}: {order(rows, s):.3f}" for s in STEPPERS) + " (where the median error is below 0.05 rad).")
    figure, axes = pyplot().subplots(figsize=(7, 4.3))
    for scheme, colour in zip(STEPPERS, ("C0", "C1")):
        dts, values, p90 = np.array([[r["dt"]] + r["attitude"] for r in rows if r["scheme"] == scheme]).T
        axes.loglog(dts, values, "o-", color=colour, label=f"{scheme}, median (order {order(rows, scheme):.2f})")
        axes.loglog(dts, p90, "--", color=colour, alpha=0.6, label=f"{scheme}, 90th percentile")
    axes.set(xlabel="dt (fs)", ylabel=f"attitude error after {T:g} ps (rad)")
    axes.legend(fontsize=8)
    page.figure(figure, "errors", "Free rotation against FreeRotor: NoSquish is second order, the first-order update first.")

STUDY = Study("rotation_accuracy", "Free rotation alone: approximate schemes against the exact rotor",
              "In free rotation NO_SQUISH is second order in the step, and matching the exact rotor to 1e-6 rad over 1 ps "
              "would cost it more than ten times what the exact rotor costs at 2 fs.", report, run=run, method="""
1000 random asymmetric tops of about a water's moments at 300 K rotate freely for T = 1 ps by NO_SQUISH (numpy, as
`numerics/NoSquish.h`) and a first-order update, against `FreeRotor.evolve(T)`; `RigidBodyIntegrator` follows both
references to rounding (`tests/python/test_studies_cost.py`). The cost: force-free bodies, CPU platform, 1 thread.""",
              caveats="With forces both integrators are second order: the free-rotation error is only the part of the "
                      "splitting error that Exact removes.")
