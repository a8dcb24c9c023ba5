"""Systems and measurements shared by the Python tests and the benchmarks (tests/python, which the
benchmarks put on sys.path; not part of the installed package).

Systems
    alanineDipeptide()
        Alanine dipeptide (ACE-ALA-NME, all hydrogens, in vacuum) as an ``openmm.app.PDBFile``: a
        solute for ``Modeller.addSolvent``, with names the amber14 force field matches.
    waterBox(model, molecules=None, edge=None, ...)
        A periodic box of water built with ``openmm.app`` (Modeller and ForceField), PME, rigid water:
        ``(topology, positions, system)``.
    randomRotation(rng)
        A rotation matrix uniformly distributed on SO(3).

Measuring
    particleMasses(), degreesOfFreedom(), energyDrift(); MOLAR_GAS_CONSTANT,
    WATERS_PER_CUBIC_NANOMETRE.

rigidtesting.bodies
    What the tests measure of the bodies (principal moments, kinds, the kinetic energies of
    translation and rotation, degrees of freedom), computed from the State alone.

rigidtesting.samplingerror
    The near-equilibrium estimate of the configuration-space KL divergence from shadow work
    (``configurationKL``), and a 1-D harmonic oscillator whose exact value is known, shared by
    benchmarks/studies/sampling_error.py and the test suite.

rigidtesting.stress
    The stability stress scenarios (extreme body shapes in a hot bath, a fast spinning body, hot
    clusters and water) and their measurements, shared by benchmarks/studies/stress.py and the test suite.
"""

import io

import numpy as np
import openmm
from openmm import app, unit

__all__ = ["alanineDipeptide", "waterBox", "degreesOfFreedom", "randomRotation", "particleMasses", "energyDrift",
           "MOLAR_GAS_CONSTANT", "WATERS_PER_CUBIC_NANOMETRE"]

MOLAR_GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
WATERS_PER_CUBIC_NANOMETRE = 33.4  # liquid water near 300 K and 1 bar

_ALANINE_DIPEPTIDE_PDB = """\
ATOM      1  H1  ACE     1       2.000   1.000  -0.000
ATOM      2  CH3 ACE     1       2.000   2.090   0.000
ATOM      3  H2  ACE     1       1.486   2.454   0.890
ATOM      4  H3  ACE     1       1.486   2.454  -0.890
ATOM      5  C   ACE     1       3.427   2.641  -0.000
ATOM      6  O   ACE     1       4.391   1.877  -0.000
ATOM      7  N   ALA     2       3.555   3.970  -0.000
ATOM      8  H   ALA     2       2.733   4.556  -0.000
ATOM      9  CA  ALA     2       4.853   4.614  -0.000
ATOM     10  HA  ALA     2       5.408   4.316   0.890
ATOM     11  CB  ALA     2       5.661   4.221  -1.232
ATOM     12  HB1 ALA     2       5.123   4.521  -2.131
ATOM     13  HB2 ALA     2       6.630   4.719  -1.206
ATOM     14  HB3 ALA     2       5.809   3.141  -1.241
ATOM     15  C   ALA     2       4.713   6.129   0.000
ATOM     16  O   ALA     2       3.601   6.653   0.000
ATOM     17  N   NME     3       5.846   6.835   0.000
ATOM     18  H   NME     3       6.737   6.359  -0.000
ATOM     19  C   NME     3       5.846   8.284   0.000
ATOM     20  H1  NME     3       4.819   8.648   0.000
ATOM     21  H2  NME     3       6.360   8.648   0.890
ATOM     22  H3  NME     3       6.360   8.648  -0.890
TER
END
"""


def alanineDipeptide():
    """Alanine dipeptide (ACE-ALA-NME, 22 atoms) in vacuum: an openmm.app.PDBFile."""
    return app.PDBFile(io.StringIO(_ALANINE_DIPEPTIDE_PDB))


# ---------------------------------------------------------------------------------------------------
# Water


def waterBox(model="tip4pew", molecules=None, edge=None, forceField=None, solute=None, **options):
    """A periodic cubic box of rigid water built with openmm.app: (topology, positions, system).

    model: Modeller.addSolvent's water model ("tip3p", "spce", "tip4pew", "tip5p", ...).
    molecules: how many waters to add, or edge: the edge of the cubic box in nm (give one of the two);
    with neither, 500 waters. forceField: an ``app.ForceField``, or file names for one (default
    ``"<model>.xml"`` from openmm's data). solute: an ``app.PDBFile`` (or anything with ``topology`` and
    ``positions``) to solvate; it comes first in the topology. options go to
    ``ForceField.createSystem``; unless given there: PME, a 0.9 nm cutoff (at most 0.45 of the edge
    when the edge is given), ``rigidWater=True``, ``ewaldErrorTolerance=5e-4``.
    """
    if molecules is not None and edge is not None:
        raise ValueError("waterBox: give the number of molecules or the edge of the box, not both")
    if forceField is None:
        forceField = app.ForceField(f"{model}.xml")
    elif not isinstance(forceField, app.ForceField):
        forceField = app.ForceField(*([forceField] if isinstance(forceField, str) else forceField))
    if solute is not None:
        modeller = app.Modeller(solute.topology, solute.positions)
    else:
        modeller = app.Modeller(app.Topology(), [])
    if edge is not None:
        modeller.addSolvent(forceField, model=model, boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
        cutoff = min(0.9, 0.45*edge)
    else:
        modeller.addSolvent(forceField, model=model, numAdded=500 if molecules is None else molecules)
        cutoff = 0.9
    settings = dict(nonbondedMethod=app.PME, nonbondedCutoff=cutoff*unit.nanometer, rigidWater=True,
                    ewaldErrorTolerance=5e-4)
    settings.update(options)
    system = forceField.createSystem(modeller.topology, **settings)
    return modeller.topology, modeller.positions, system


def degreesOfFreedom(system):
    """OpenMM's count for a System, as app.StateDataReporter makes it: 3 per massive particle, less one per
    constraint that involves a massive particle and 3 more with a CMMotionRemover (what a stock
    integrator's temperature uses)."""
    massive = [system.getParticleMass(i) > 0*unit.dalton for i in range(system.getNumParticles())]
    constraints = sum(1 for i in range(system.getNumConstraints())
                      if any(massive[j] for j in system.getConstraintParameters(i)[:2]))
    remover = any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
    return 3*sum(massive) - constraints - (3 if remover else 0)


# ---------------------------------------------------------------------------------------------------
# Rotations, masses and measurements


def randomRotation(rng):
    """A rotation matrix uniformly distributed on SO(3), from a random unit quaternion (rng: a numpy
    ``Generator``)."""
    quaternion = rng.normal(size=4)
    w, x, y, z = quaternion/np.linalg.norm(quaternion)
    return np.array([[1 - 2*(y*y + z*z), 2*(x*y - w*z), 2*(x*z + w*y)],
                     [2*(x*y + w*z), 1 - 2*(x*x + z*z), 2*(y*z - w*x)],
                     [2*(x*z - w*y), 2*(y*z + w*x), 1 - 2*(x*x + y*y)]])


def particleMasses(system):
    """The System's particle masses in amu, as a numpy array (0 for virtual sites)."""
    return np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])


def energyDrift(times, energies, dof):
    """Energy drift and fluctuation of a run: the slope of the least-squares line through the total
    energies (kJ/mol) against time (ps), in kJ/mol/ns per degree of freedom, and the standard deviation
    of the energies about that line (kJ/mol)."""
    from .stress import energy_drift  # the one fit (its residual's mean is 0, so its RMS is the deviation)
    slope, _, fluctuation = energy_drift(times, energies)
    return float(slope*1000/dof), float(fluctuation)
