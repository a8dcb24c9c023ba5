#!/usr/bin/env python
"""The exact free rigid rotor: the example of van Zon and Schofield, J. Comput. Phys. 225 (2007) 145, Section 5.

A body of six unit masses at (+-a, 0, 0), (0, +-b, 0), (0, 0, +-c) with a = 3, b = 2, c = 1 has the
principal moments I = (2(b^2 + c^2), 2(a^2 + c^2), 2(a^2 + b^2)) = (10, 20, 26). It starts at
A(0) = identity with the body-frame angular velocity omega(0) = (1, 15, 1): mostly a spin about the
middle axis, which is unstable, so the motion is far from a small wobble about y.

The script
1. prints omega and the attitude matrix A at t = 1 and t = 10 next to reference values from an
   independent DOP853 integration of Euler's equations and dA/dt = -W(omega) A (rtol 1e-14, trusted to
   about 1e-11; docs/free-rotor-notes.md), with the largest deviation;
2. redraws the paper's Fig. 3: (a) the body-frame components of omega against t, (b) the x-z
   projection of the lab-frame positions r_lab = A^T r_body of the masses at (a,0,0), (0,b,0), (0,0,c),
   and writes it to examples/output/free_rotor_fig3.png.

Step: none. FreeRotor evaluates the exact solution (Jacobi elliptic functions) at any time, so nothing
is integrated step by step and nothing depends on a step size; the 2001 times of the figure only
sample the curves for drawing. (The integrators' free drift is this same exact motion over each step.)

Run: python examples/free_rotor.py   (needs openmmrigid and numpy; the figure needs matplotlib:
pip install "openmm-rigid[examples]"; without it the comparison still runs and no figure is drawn)
"""

from pathlib import Path

import numpy as np

from openmmrigid import FreeRotor

A_LENGTH, B_LENGTH, C_LENGTH = 3.0, 2.0, 1.0
OUTPUT = Path(__file__).resolve().parent / "output" / "free_rotor_fig3.png"

# DOP853 reference values (notes, "Reference values"): t -> (omega, A).
REFERENCE = {
    1.0: ([-3.82816674585263, -14.38031707420242, 3.12299788521524],
          [[-0.04774788417409, -0.03951390794745, -0.99807754740582],
           [-0.29760763575414, -0.95327227334549, 0.05197757219765],
           [-0.95349348959378, 0.29951731827968, 0.03375709337043]]),
    10.0: ([-8.93297814786449, 10.95152357192214, 7.17715832766704],
           [[0.34695161257479, -0.38350804757471, 0.85588910261618],
            [0.70961805857052, 0.70403757099296, 0.02780844441733],
            [-0.61324284706982, 0.59770617871641, 0.51641120673539]]),
}


def sixMassBody():
    """Body-frame positions of the six unit masses and their inertia tensor (diagonal: principal axes)."""
    positions = np.array([[A_LENGTH, 0, 0], [-A_LENGTH, 0, 0], [0, B_LENGTH, 0],
                          [0, -B_LENGTH, 0], [0, 0, C_LENGTH], [0, 0, -C_LENGTH]], dtype=float)
    inertia = sum(np.dot(r, r) * np.eye(3) - np.outer(r, r) for r in positions)
    return positions, inertia


def row3(values):
    return " ".join(f"{x:+18.14f}" for x in values)


def compareWithReference(rotor):
    times = np.array(sorted(REFERENCE))
    omegas, attitudes = rotor.evolve(times)
    worst = 0.0
    for t, omega, attitude in zip(times, omegas, attitudes):
        referenceOmega, referenceAttitude = (np.array(x) for x in REFERENCE[t])
        deviation = max(np.abs(omega - referenceOmega).max(), np.abs(attitude - referenceAttitude).max())
        worst = max(worst, deviation)
        print(f"t = {t:<4g}{'':59}reference (DOP853)")
        print(f"  omega {row3(omega)}   {row3(referenceOmega)}")
        for row in range(3):
            print(f"  {'A' if row == 0 else ' '}     {row3(attitude[row])}   {row3(referenceAttitude[row])}")
        print(f"  max deviation {deviation:.2e}")
    print(f"largest deviation from the DOP853 reference: {worst:.2e} (the reference is trusted to about 1e-11)")
    return worst


def drawFigure3(rotor, path):
    """Draw the figure into `path`; False (and say how to get it) where matplotlib is not installed."""
    try:
        import matplotlib
    except ImportError:
        print('no figure: matplotlib is not installed (pip install "openmm-rigid[examples]", or pip install matplotlib)')
        return False
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    times = np.linspace(0.0, 5.0, 2001)
    omegas, attitudes = rotor.evolve(times)
    fig, (left, right) = plt.subplots(1, 2, figsize=(12.5, 4.6))
    for k, (name, style) in enumerate(zip("xyz", ["-", "--", ":"])):
        left.plot(times, omegas[:, k], style, label=rf"$\tilde\omega_{name}$")
    left.set_xlabel("t")
    left.set_ylabel(r"$\tilde\omega$ (body frame)")
    left.set_title("(a) angular velocity")
    left.legend(loc="lower left")
    # r_lab = A^T r_body for the masses on the long, middle and short axes.
    axes = {"long axis (a,0,0)": [A_LENGTH, 0, 0], "middle axis (0,b,0)": [0, B_LENGTH, 0],
            "short axis (0,0,c)": [0, 0, C_LENGTH]}
    for (label, point), style in zip(axes.items(), ["-", "--", ":"]):
        lab = np.einsum("nji,j->ni", attitudes, np.array(point))
        right.plot(lab[:, 0], lab[:, 2], style, label=label)
    right.set_aspect("equal")
    right.set_xlabel("x (lab)")
    right.set_ylabel("z (lab)")
    right.set_title("(b) x-z projection of the axes, 0 <= t <= 5")
    right.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    fig.suptitle(r"Exact free rotor, I = (10, 20, 26), $\tilde\omega(0)$ = (1, 15, 1) (van Zon & Schofield 2007, Fig. 3)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def main():
    positions, inertia = sixMassBody()
    moments = np.diag(inertia)
    print(f"six unit masses: principal moments {moments} (inertia tensor diagonal: {np.allclose(inertia, np.diag(moments))})")
    rotor = FreeRotor(moments, [1.0, 15.0, 1.0], np.eye(3))
    print(rotor)
    compareWithReference(rotor)
    if drawFigure3(rotor, OUTPUT):
        print(f"wrote {OUTPUT}")


if __name__ == "__main__":
    main()
