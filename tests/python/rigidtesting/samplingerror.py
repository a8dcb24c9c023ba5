"""The near-equilibrium estimate of the configuration-space KL divergence of a Langevin integrator's
sampled distribution from the Boltzmann distribution, from shadow work (Sivak, Chodera and Crooks,
Phys. Rev. X 3, 011007 (2013); Fass et al., Entropy 20, 318 (2018)).

The protocol, for each of n samples: a configuration from the equilibrium distribution pi_x and
velocities from Maxwell-Boltzmann (together: pi); T steps of the integrator, summing the shadow work
w_pi (in kT); at their end the sampled distribution rho is reached (T long enough); the velocities
drawn again (the state is then drawn from omega = rho_x times Maxwell-Boltzmann); T more steps,
summing w_omega. By the chain rule of the KL divergence, D(rho_x || pi_x) = D(rho || pi) - D(rho ||
omega), and each of those is, near equilibrium, half the excess work of relaxing to rho from pi and
from omega; the steady-state work cancels in their difference:

    D(rho_x || pi_x) ~ (<w_pi> - <w_omega>) / 2.

Its error: the standard error of the mean of the paired differences (w_pi - w_omega)/2.
"""

import numpy as np

__all__ = ["configurationKL", "harmonicLangevinSamples", "harmonicConfigurationKL"]


def configurationKL(workFromEquilibrium, workFromResampled):
    """The near-equilibrium estimate of D(rho_x || pi_x) and its standard error, from the shadow works
    (in kT) of the n samples' two halves (arrays of length n, paired)."""
    first, second = np.asarray(workFromEquilibrium, float), np.asarray(workFromResampled, float)
    if first.shape != second.shape or first.ndim != 1 or len(first) < 2:
        raise ValueError("configurationKL: give two equally long 1-D arrays of at least 2 paired shadow works")
    halves = 0.5*(first - second)
    return halves.mean(), halves.std(ddof=1)/np.sqrt(len(halves))


def _stage(name, x, v, h, omega2, c, rng):
    """One stage of a splitting on arrays of unit-mass 1-D oscillators (kT = 1): returns x, v and the
    energy change it made, split into deterministic (shadow work) and stochastic (heat) parts."""
    before = 0.5*v*v + 0.5*omega2*x*x
    if name == "V":
        v = v - omega2*x*h
    elif name == "R":
        x = x + v*h
    else:  # "O"
        v = c*v + np.sqrt(1.0 - c*c)*rng.standard_normal(v.shape)
    change = 0.5*v*v + 0.5*omega2*x*x - before
    return x, v, change


def harmonicLangevinSamples(splitting, omega, dt, friction, steps, samples, seed):
    """The shadow works (kT) of the protocol above for a 1-D harmonic oscillator (unit mass, kT = 1,
    U = omega^2 x^2 / 2) under a Langevin splitting written as openmmtools writes it ("V R O R V":
    BAOAB; "R V O V R": ABOBA; "O V R V O": OBABO; V and R of a whole step are split evenly among
    their occurrences, O is the exact Ornstein-Uhlenbeck step of the whole step split likewise). The
    equilibrium configurations are drawn exactly. Returns (w_pi, w_omega), each of length samples."""
    rng = np.random.default_rng(seed)
    stages = splitting.split()
    counts = {name: stages.count(name) for name in "VRO"}
    x = rng.standard_normal(samples)/omega
    works = []
    for half in range(2):
        v = rng.standard_normal(samples)
        work = np.zeros(samples)
        for _ in range(steps):
            for name in stages:
                h = dt/counts[name]
                c = np.exp(-friction*h)
                x, v, change = _stage(name, x, v, h, omega*omega, c, rng)
                if name != "O":
                    work += change
        works.append(work)
    return works[0], works[1]


def harmonicConfigurationKL(splitting, omega, dt, friction):
    """The exact D(rho_x || pi_x) of the same integrator for the harmonic oscillator: its step is a
    linear map z' = A z + B xi of z = (x, v), so rho is Gaussian with the covariance S that solves
    S = A S A^T + B B^T, and rho_x = N(0, S_xx) against pi_x = N(0, 1/omega^2)."""
    stages = splitting.split()
    counts = {name: stages.count(name) for name in "VRO"}
    A, noise = np.eye(2), np.zeros((2, 2))
    for name in stages:
        h = dt/counts[name]
        if name == "V":
            M, N = np.array([[1.0, 0.0], [-omega*omega*h, 1.0]]), np.zeros((2, 2))
        elif name == "R":
            M, N = np.array([[1.0, h], [0.0, 1.0]]), np.zeros((2, 2))
        else:
            c = np.exp(-friction*h)
            M, N = np.array([[1.0, 0.0], [0.0, c]]), np.array([[0.0, 0.0], [0.0, 1.0 - c*c]])
        A, noise = M @ A, M @ noise @ M.T + N
    S = np.eye(2)
    for _ in range(100000):  # the fixed point of S -> A S A^T + noise (A is a contraction for friction > 0)
        following = A @ S @ A.T + noise
        if np.allclose(following, S, rtol=1e-15, atol=0):
            break
        S = following
    ratio = S[0, 0]*omega*omega
    return 0.5*(ratio - 1.0 - np.log(ratio))
