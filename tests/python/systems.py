"""Test systems and measurements shared by the Python tests of the integrators.

From rigidtesting.stress (where the stress scenarios of tests and benchmarks build on them),
re-exported here:
- cluster(): an isolated cluster of small rigid molecules of every kind (asymmetric, symmetric and
  spherical tops, linear molecules, single-particle bodies) and free atoms, Lennard-Jones + Coulomb
  without cutoff as a CustomBondForce (double precision on Reference and CPU).
- water_box(): a small periodic box of TIP3P or TIP4P-Ew water from openmm.app (PME), minimised,
  with Maxwell-Boltzmann velocities.
- rigid_motion(): the exact free motion of a set of bodies, from openmmrigid.FreeRotor.
- energy_drift() and block_drift(), positions_of(), velocities_of(), platform_and_properties().

Defined here: the platforms to test (PLATFORMS, GPU_PLATFORMS), minimize(), small_water_box() and make_context(),
mixed_system() (alanine dipeptide, flexible with HBonds constraints, in rigid TIP3P water with a
rigid benzene, a rigid linear CO2, a Na+ ion as a single-particle body and a free Cl- ion),
run_energies(), and the copies of an integrator (COPY_METHODS, copy_integrator()).
"""

import io

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit

import openmmrigid
# The systems and measurements that the stress scenarios build on live in rigidtesting (shared with
# benchmarks/studies/stress.py); the tests use them from there.
import rigidtesting
from rigidtesting import randomRotation  # noqa: F401
from rigidtesting.stress import (BOLTZMANN, KJ_PER_MOL_PER_NM, WATER_MODELS, Cluster, RigidMotion,  # noqa: F401
                                 Solvated, _prepare, block_drift, cluster, energy_drift, platform_and_properties,
                                 positions_of, rigid_motion, velocities_of, water_box)


def _has_rigid_kernels(name):
    """Whether the platform exists here and openmmrigid registered its kernels with it."""
    try:
        return openmm.Platform.getPlatformByName(name).supportsKernels(["IntegrateRigidBodyStep"])
    except Exception:
        return False


#: The GPU platforms (common compute) that are present with the plugin's kernels: OpenCL through PoCL
#: on a machine without a GPU, CUDA where there is a driver.
GPU_PLATFORMS = [name for name in ("OpenCL", "CUDA") if _has_rigid_kernels(name)]
#: Every platform the workflow tests run on.
PLATFORMS = ["Reference", "CPU"] + GPU_PLATFORMS


def minimize(context, tolerance=10, maxIterations=100):
    """openmm.LocalEnergyMinimizer.minimize(context, ...), done on the CPU platform for a GPU
    platform's Context (OpenMM's minimiser crashes on PoCL's OpenCL) and the result set in context."""
    if context.getPlatform().getName() not in ("OpenCL", "CUDA"):
        openmm.LocalEnergyMinimizer.minimize(context, tolerance, maxIterations)
        return
    state = context.getState(getPositions=True)
    helper = openmm.Context(context.getSystem(), openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName("CPU"))
    helper.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
    helper.setPositions(state.getPositions())
    openmm.LocalEnergyMinimizer.minimize(helper, tolerance, maxIterations)
    context.setPositions(helper.getState(getPositions=True).getPositions())


def small_water_box(equilibrationSteps):
    """About 100 TIP3P waters (a 1.5 nm box) with a cheap reaction-field cutoff of 0.6 nm and no
    CMMotionRemover (so that translation and rotation have 3 degrees of freedom per water each),
    minimised and thermalised at 300 K with LangevinMiddleIntegrator + SETTLE (friction 10/ps, 2 fs,
    equilibrationSteps steps on the CPU platform): the System and the final State."""
    forcefield = app.ForceField("amber14/tip3p.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forcefield, model="tip3p", boxSize=openmm.Vec3(1.5, 1.5, 1.5) * unit.nanometer)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.CutoffPeriodic,
                                     nonbondedCutoff=0.6 * unit.nanometer, rigidWater=True, removeCMMotion=False)
    thermostat = openmm.LangevinMiddleIntegrator(300 * unit.kelvin, 10 / unit.picosecond, 2 * unit.femtoseconds)
    thermostat.setRandomNumberSeed(7)
    context = openmm.Context(system, thermostat, *platform_and_properties("CPU"))
    context.setPositions(modeller.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 200)
    context.setVelocitiesToTemperature(300 * unit.kelvin, 7)
    thermostat.step(equilibrationSteps)
    return system, context.getState(getPositions=True, getVelocities=True)


def make_context(system, integrator, platform_name):
    platform, properties = platform_and_properties(platform_name)
    return openmm.Context(system, integrator, platform, properties)


def start_context(system, integrator, platform_name, positions, velocities):
    """make_context() with the positions and velocities set."""
    context = make_context(system, integrator, platform_name)
    context.setPositions(positions)
    context.setVelocities(velocities)
    return context


# ------------------------------------------------------------------------------------------------
# Small rigid molecules, each: (name, masses, body-frame coordinates in nm, charges, sigma, epsilon)
# ------------------------------------------------------------------------------------------------


# ------------------------------------------------------------------------------------------------
# The exact free motion of rigid bodies
# ------------------------------------------------------------------------------------------------


# ------------------------------------------------------------------------------------------------
# openmm.app systems
# ------------------------------------------------------------------------------------------------


# Benzene (OPLS-AA-like charges and Lennard-Jones) and CO2 (TraPPE). No bonded terms: both move as
# rigid bodies, so their internal geometry never changes.
SMALL_MOLECULES_XML = """\
<ForceField>
 <AtomTypes>
  <Type name="rigidtest-bnz-C" class="rigidtest-bnz-C" element="C" mass="12.011"/>
  <Type name="rigidtest-bnz-H" class="rigidtest-bnz-H" element="H" mass="1.008"/>
  <Type name="rigidtest-co2-C" class="rigidtest-co2-C" element="C" mass="12.011"/>
  <Type name="rigidtest-co2-O" class="rigidtest-co2-O" element="O" mass="15.999"/>
 </AtomTypes>
 <Residues>
  <Residue name="BNZ">
%s
  </Residue>
  <Residue name="CO2">
   <Atom name="C" type="rigidtest-co2-C" charge="0.7"/>
   <Atom name="O1" type="rigidtest-co2-O" charge="-0.35"/>
   <Atom name="O2" type="rigidtest-co2-O" charge="-0.35"/>
   <Bond atomName1="C" atomName2="O1"/>
   <Bond atomName1="C" atomName2="O2"/>
  </Residue>
 </Residues>
 <NonbondedForce coulomb14scale="0.8333333333333334" lj14scale="0.5">
  <UseAttributeFromResidue name="charge"/>
  <Atom type="rigidtest-bnz-C" sigma="0.355" epsilon="0.29288"/>
  <Atom type="rigidtest-bnz-H" sigma="0.242" epsilon="0.12552"/>
  <Atom type="rigidtest-co2-C" sigma="0.28" epsilon="0.2245"/>
  <Atom type="rigidtest-co2-O" sigma="0.305" epsilon="0.6568"/>
 </NonbondedForce>
</ForceField>
"""


def _benzene_residue_xml():
    lines = []
    for k in range(6):
        lines.append(f'   <Atom name="C{k + 1}" type="rigidtest-bnz-C" charge="-0.115"/>')
    for k in range(6):
        lines.append(f'   <Atom name="H{k + 1}" type="rigidtest-bnz-H" charge="0.115"/>')
    for k in range(6):
        lines.append(f'   <Bond atomName1="C{k + 1}" atomName2="C{(k + 1) % 6 + 1}"/>')
        lines.append(f'   <Bond atomName1="C{k + 1}" atomName2="H{k + 1}"/>')
    return "\n".join(lines)


def _add_molecule(modeller, residueName, atoms, bonds, centre, rotation):
    """Add one residue (atoms: (name, element symbol, body-frame position in nm)) to the Modeller."""
    topology = app.Topology()
    chain = topology.addChain()
    residue = topology.addResidue(residueName, chain)
    added = [topology.addAtom(name, app.Element.getBySymbol(symbol), residue) for name, symbol, _ in atoms]
    for i, j in bonds:
        topology.addBond(added[i], added[j])
    positions = [openmm.Vec3(*(rotation @ np.asarray(xyz) + centre)) for _, _, xyz in atoms] * unit.nanometer
    modeller.add(topology, positions)


def mixed_system(seed=11, size=2.2, cutoff=0.8):
    """Alanine dipeptide (HBonds constraints), rigid benzene, rigid CO2, Na+ and Cl- in TIP3P water.

    Returns a Solvated whose extra attributes name the parts: peptide, benzene, co2, sodium,
    chloride (particle indices) and waters (one list of three indices per water).
    """
    rng = np.random.default_rng(seed)
    forcefield = app.ForceField("amber14-all.xml", "amber14/tip3p.xml",
                                io.StringIO(SMALL_MOLECULES_XML % _benzene_residue_xml()))
    peptide = rigidtesting.alanineDipeptide()
    modeller = app.Modeller(peptide.topology, peptide.positions)
    peptidePositions = np.array(modeller.positions.value_in_unit(unit.nanometer))
    modeller.positions = [openmm.Vec3(*x) for x in peptidePositions - peptidePositions.mean(axis=0)
                          + 0.5 * size] * unit.nanometer
    half, quarter = 0.5 * size, 0.25 * size
    ring, ch = 0.1397, 0.1084
    benzene = [(f"C{k + 1}", "C", ring * np.array([np.cos(k * np.pi / 3), np.sin(k * np.pi / 3), 0.0]))
               for k in range(6)]
    benzene += [(f"H{k + 1}", "H", (ring + ch) * np.array([np.cos(k * np.pi / 3), np.sin(k * np.pi / 3), 0.0]))
                for k in range(6)]
    benzeneBonds = [(k, (k + 1) % 6) for k in range(6)] + [(k, k + 6) for k in range(6)]
    _add_molecule(modeller, "BNZ", benzene, benzeneBonds, np.array([half + quarter] * 3), randomRotation(rng))
    co2 = [("C", "C", [0.0, 0.0, 0.0]), ("O1", "O", [0.0, 0.0, 0.116]), ("O2", "O", [0.0, 0.0, -0.116])]
    _add_molecule(modeller, "CO2", co2, [(0, 1), (0, 2)], np.array([quarter, quarter, half + quarter]),
                  randomRotation(rng))
    _add_molecule(modeller, "NA", [("NA", "Na", [0.0, 0.0, 0.0])], [], np.array([quarter, half + quarter, quarter]),
                  np.eye(3))
    _add_molecule(modeller, "CL", [("CL", "Cl", [0.0, 0.0, 0.0])], [], np.array([half + quarter, quarter, quarter]),
                  np.eye(3))
    modeller.topology.setPeriodicBoxVectors(np.eye(3) * size * unit.nanometer)
    modeller.addSolvent(forcefield, model="tip3p", boxSize=openmm.Vec3(size, size, size) * unit.nanometer)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.PME,
                                     nonbondedCutoff=cutoff * unit.nanometer, switchDistance=(cutoff - 0.1) * unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True, ewaldErrorTolerance=1e-4)
    parts = {"peptide": [], "benzene": [], "co2": [], "sodium": [], "chloride": [], "waters": []}
    names = {"ACE": "peptide", "ALA": "peptide", "NME": "peptide", "BNZ": "benzene", "CO2": "co2",
             "NA": "sodium", "CL": "chloride"}
    for residue in modeller.topology.residues():
        indices = [atom.index for atom in residue.atoms()]
        if residue.name == "HOH":
            parts["waters"].append(indices)
        else:
            parts[names[residue.name]].extend(indices)
    frozen = parts["benzene"] + parts["co2"]
    result = _prepare(modeller.topology, modeller.positions, system, seed, frozen=frozen)
    for name, indices in parts.items():
        setattr(result, name, indices)
    # The frozen bodies were held still during minimisation; give them thermal rigid motion now.
    for body in (parts["benzene"], parts["co2"]):
        masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in body])
        relative = result.positions[body] - masses @ result.positions[body] / masses.sum()
        velocity = rng.normal(scale=np.sqrt(BOLTZMANN * 300.0 / masses.sum()), size=3)
        omega = rng.normal(scale=3.0, size=3)
        result.velocities[body] = velocity + np.cross(omega, relative)
    return result


# ------------------------------------------------------------------------------------------------
# Measurements
# ------------------------------------------------------------------------------------------------


def run_energies(context, integrator, steps, interval):
    """Total energies (kJ/mol) at t = 0, interval, 2 interval, ... steps (in steps), with their times (ps)."""
    times, energies = [], []
    dt = integrator.getStepSize().value_in_unit(unit.picosecond)
    for k in range(0, steps + 1, interval):
        if k > 0:
            integrator.step(interval)
        state = context.getState(getEnergy=True)
        energies.append((state.getPotentialEnergy() + state.getKineticEnergy()).value_in_unit(unit.kilojoule_per_mole))
        times.append(k * dt)
    return np.array(times), np.array(energies)


# ------------------------------------------------------------------------------------------------
# Copies of an integrator, every way a user can make one
# ------------------------------------------------------------------------------------------------

#: openmm.XmlSerializer.deserialize() and clone() are no way to copy one: openmm is not patched on
#: import, so they return a plain openmm.Integrator proxy; openmmrigid.deserializeIntegrator() reads the XML.
COPY_METHODS = ["pickle", "copy", "deepcopy", "deserializeIntegrator"]


def copy_integrator(integrator, method):
    """A copy of the integrator made by `method`, one of COPY_METHODS."""
    import copy
    import pickle
    if method == "pickle":
        return pickle.loads(pickle.dumps(integrator))
    if method == "copy":
        return copy.copy(integrator)
    if method == "deepcopy":
        return copy.deepcopy(integrator)
    if method == "deserializeIntegrator":
        return openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(integrator))
    raise ValueError(f"unknown copy method {method!r}; expected one of {COPY_METHODS}")
