"""Test systems and measurements shared by the physics tests of RigidBodyIntegrator
(test_integrator_physics.py).

- cluster(): an isolated cluster of small rigid molecules of every kind (asymmetric, symmetric and
  spherical tops, linear molecules, single-particle bodies) and free atoms, interacting by
  Lennard-Jones + Coulomb without cutoff. The pair terms are a CustomBondForce over all
  intermolecular pairs, evaluated in double precision on both the Reference and the CPU platform
  (the CPU platform's NonbondedForce works in single precision, whose rounding noise would hide the
  1e-10 conservation laws and the 1e-8 time reversal being tested).
- water_box(): a small periodic box of TIP3P or TIP4P-Ew water from openmm.app (ForceField +
  Modeller.addSolvent, PME), minimised, with Maxwell-Boltzmann velocities.
- mixed_system(): alanine dipeptide (flexible, HBonds constraints) in rigid TIP3P water with a rigid
  benzene, a rigid linear CO2, a Na+ ion (a single-particle body) and a free Cl- ion.
- rigid_motion(): the exact free motion of a set of bodies, computed here from their initial
  state with openmmrigid.FreeRotor (inertia tensor, principal axes and omega from L computed here).
- energy_drift(): the least-squares slope of the total energy.
"""

import io

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit

import openmmrigid

KJ_PER_MOL_PER_NM = 138.935456  # Coulomb's constant, kJ mol^-1 nm e^-2 (OpenMM's ONE_4PI_EPS0)
BOLTZMANN = 0.00831446261815324  # kJ/mol/K


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


def platform_and_properties(name, precision="double"):
    """The platform and the properties the tests use with it (deterministic forces on CPU; a GPU
    platform in the given precision, double unless asked)."""
    platform = openmm.Platform.getPlatformByName(name)
    if name == "CPU":
        properties = {"DeterministicForces": "true"}
    elif name in ("OpenCL", "CUDA"):
        properties = {"Precision": precision}
    else:
        properties = {}
    return platform, properties


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


def make_context(system, integrator, platform_name):
    platform, properties = platform_and_properties(platform_name)
    return openmm.Context(system, integrator, platform, properties)


# ------------------------------------------------------------------------------------------------
# Small rigid molecules, each: (name, masses, body-frame coordinates in nm, charges, sigma, epsilon)
# ------------------------------------------------------------------------------------------------

def _tetrahedron(length):
    return length / np.sqrt(3.0) * np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)


def _water_like():
    # Asymmetric top (all three principal moments differ).
    angle = np.radians(104.52)
    oh = 0.09572
    coordinates = np.array([[0.0, 0.0, 0.0],
                            [oh * np.sin(angle / 2), oh * np.cos(angle / 2), 0.0],
                            [-oh * np.sin(angle / 2), oh * np.cos(angle / 2), 0.0]])
    return ("water", [15.999, 1.008, 1.008], coordinates, [-0.834, 0.417, 0.417],
            [0.315, 0.1, 0.1], [0.636, 0.0, 0.0])


def _ammonia_like():
    # Symmetric top: N above an equilateral triangle of H.
    h = 0.0381
    r = 0.0939
    coordinates = [[0.0, 0.0, h]]
    for k in range(3):
        phi = 2 * np.pi * k / 3
        coordinates.append([r * np.cos(phi), r * np.sin(phi), 0.0])
    return ("ammonia", [14.007, 1.008, 1.008, 1.008], np.array(coordinates), [-0.9, 0.3, 0.3, 0.3],
            [0.325, 0.1, 0.1, 0.1], [0.711, 0.0, 0.0, 0.0])


def _methane_like():
    # Spherical top: C at the centre of a regular tetrahedron of H.
    coordinates = np.vstack([[0.0, 0.0, 0.0], _tetrahedron(0.109)])
    return ("methane", [12.011] + [1.008] * 4, coordinates, [-0.24, 0.06, 0.06, 0.06, 0.06],
            [0.35, 0.25, 0.25, 0.25, 0.25], [0.276, 0.125, 0.125, 0.125, 0.125])


def _carbon_dioxide():
    # Linear triatomic.
    co = 0.116
    return ("co2", [12.011, 15.999, 15.999], np.array([[0.0, 0.0, 0.0], [0.0, 0.0, co], [0.0, 0.0, -co]]),
            [0.7, -0.35, -0.35], [0.28, 0.305, 0.305], [0.224, 0.657, 0.657])


def _carbon_monoxide():
    # Linear diatomic with unequal masses.
    return ("co", [12.011, 15.999], np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.1128]]), [0.02, -0.02],
            [0.33, 0.31], [0.4, 0.5])


def _sodium():
    # A single-particle body: translation only.
    return ("sodium", [22.99], np.zeros((1, 3)), [1.0], [0.25], [0.36])


def _chloride():
    # A free particle (in no body).
    return ("chloride", [35.45], np.zeros((1, 3)), [-1.0], [0.44], [0.42])


def _argon():
    return ("argon", [39.948], np.zeros((1, 3)), [0.0], [0.34], [0.996])


def _random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class Cluster:
    """A non-periodic System of small molecules and the state to start it from.

    Attributes: system, positions and velocities ((n, 3) arrays, nm and nm/ps), bodies (lists of
    particle indices), free (indices of particles in no body), masses, molecules (one list of
    particle indices per molecule, bodies and free atoms alike).
    """


def cluster(seed=1, spacing=0.5, grid=(3, 3, 3), temperature=300.0, drift=(0.0, 0.0, 0.0), spin=0.0,
            forces=True):
    """An isolated cluster: molecules of every kind on a grid, random orientations, thermal rigid
    velocities (each body moves rigidly: v_i = V + omega x (r_i - R)).

    drift (nm/ps) is added to every velocity and spin (rad/ps) rotates the whole cluster about the
    z axis through its centre of mass, so that total linear and angular momentum are non-zero.
    With forces=False the System holds no forces at all.
    """
    rng = np.random.default_rng(seed)
    kinds = [_water_like, _ammonia_like, _methane_like, _carbon_dioxide, _carbon_monoxide, _sodium]
    freeKinds = [_chloride, _argon]
    sites = [np.array([i, j, k], dtype=float) * spacing
             for i in range(grid[0]) for j in range(grid[1]) for k in range(grid[2])]
    # Every body kind at least twice, then waters; the last two sites hold free atoms.
    plan = kinds + kinds + [_water_like] * max(0, len(sites) - 2 * len(kinds) - 2) + freeKinds
    plan = plan[:len(sites)]
    system = openmm.System()
    positions, velocities, masses, charges, sigmas, epsilons = [], [], [], [], [], []
    bodies, free, molecules = [], [], []
    for site, make in zip(sites, plan):
        name, molMasses, coordinates, molCharges, molSigmas, molEpsilons = make()
        molMasses = np.array(molMasses)
        # Place the molecule's centre of mass on the grid site, randomly oriented.
        centre = molMasses @ coordinates / molMasses.sum()
        rotation = _random_rotation(rng)
        molPositions = (coordinates - centre) @ rotation.T + site + rng.normal(scale=0.02, size=3)
        comVelocity = rng.normal(scale=np.sqrt(BOLTZMANN * temperature / molMasses.sum()), size=3)
        relative = molPositions - molMasses @ molPositions / molMasses.sum()
        inertia = sum(m * (np.dot(r, r) * np.eye(3) - np.outer(r, r)) for m, r in zip(molMasses, relative))
        omega = np.zeros(3)
        if len(molMasses) > 1:
            moments, axes = np.linalg.eigh(inertia)
            bodyOmega = np.array([rng.normal(scale=np.sqrt(BOLTZMANN * temperature / I)) if I > 1e-9 * moments[-1]
                                  else 0.0 for I in moments])
            omega = axes @ bodyOmega
        indices = list(range(system.getNumParticles(), system.getNumParticles() + len(molMasses)))
        for k in range(len(molMasses)):
            system.addParticle(molMasses[k])
            positions.append(molPositions[k])
            velocities.append(comVelocity + np.cross(omega, relative[k]))
        masses.extend(molMasses)
        charges.extend(molCharges)
        sigmas.extend(molSigmas)
        epsilons.extend(molEpsilons)
        molecules.append(indices)
        if make in freeKinds:
            free.extend(indices)
        else:
            bodies.append(indices)
    positions = np.array(positions)
    velocities = np.array(velocities)
    masses = np.array(masses)
    centre = masses @ positions / masses.sum()
    velocities += np.asarray(drift, dtype=float) + np.cross([0.0, 0.0, spin], positions - centre)
    if forces:
        pairs = openmm.CustomBondForce(
            "4*epsilon*((sigma/r)^12 - (sigma/r)^6) + coulomb*qq/r")
        pairs.addGlobalParameter("coulomb", KJ_PER_MOL_PER_NM)
        for parameter in ("qq", "sigma", "epsilon"):
            pairs.addPerBondParameter(parameter)
        molecule = np.empty(len(masses), dtype=int)
        for index, members in enumerate(molecules):
            molecule[members] = index
        for i in range(len(masses)):
            for j in range(i + 1, len(masses)):
                if molecule[i] != molecule[j]:
                    pairs.addBond(i, j, [charges[i] * charges[j], 0.5 * (sigmas[i] + sigmas[j]),
                                         np.sqrt(epsilons[i] * epsilons[j])])
        system.addForce(pairs)
    result = Cluster()
    result.system = system
    result.positions = positions
    result.velocities = velocities
    result.bodies = bodies
    result.free = free
    result.masses = masses
    result.molecules = molecules
    return result


# ------------------------------------------------------------------------------------------------
# The exact free motion of rigid bodies
# ------------------------------------------------------------------------------------------------

class RigidMotion:
    """The exact torque-free motion of one body, from its initial positions and velocities."""

    def __init__(self, masses, positions, velocities):
        masses = np.asarray(masses, dtype=float)
        self.centre = masses @ positions / masses.sum()
        self.velocity = masses @ velocities / masses.sum()
        relative = positions - self.centre
        self.rotor = None
        self.bodyCoordinates = relative
        if len(masses) == 1:
            return
        inertia = sum(m * (np.dot(r, r) * np.eye(3) - np.outer(r, r)) for m, r in zip(masses, relative))
        moments, axes = np.linalg.eigh(inertia)       # columns of axes: principal axes (lab frame)
        if np.linalg.det(axes) < 0:
            axes[:, 0] = -axes[:, 0]
        attitude = axes.T                               # lab -> body
        angularMomentum = sum(m * np.cross(r, v - self.velocity)
                              for m, r, v in zip(masses, relative, velocities))
        bodyMomentum = attitude @ angularMomentum
        linear = moments[0] <= 1e-12 * moments[2]
        if linear:
            # The axis of a linear body carries no angular momentum; FreeRotor wants the zero moment exact.
            moments[0] = 0.0
            bodyOmega = np.array([0.0, bodyMomentum[1] / moments[1], bodyMomentum[2] / moments[2]])
        else:
            bodyOmega = bodyMomentum / moments
        self.bodyCoordinates = relative @ attitude.T
        if linear:
            self.bodyCoordinates[:, 1:] = 0.0
        self.rotor = openmmrigid.FreeRotor(moments, bodyOmega, attitude)

    def at(self, t):
        """Positions and velocities at time t (ps)."""
        if self.rotor is None:
            return self.centre + self.velocity * t + self.bodyCoordinates * 0.0, \
                np.tile(self.velocity, (len(self.bodyCoordinates), 1))
        omega, attitude = self.rotor.evolve(t)
        relative = self.bodyCoordinates @ attitude          # rows: A^T b_i
        labOmega = attitude.T @ omega
        return self.centre + self.velocity * t + relative, self.velocity + np.cross(labOmega, relative)


def rigid_motion(masses, positions, velocities, bodies, free):
    """A function t -> (positions, velocities) giving the exact free motion of every body and the
    straight-line motion of every free particle."""
    motions = [(body, RigidMotion(masses[body], positions[body], velocities[body])) for body in bodies]

    def at(t):
        r = np.array(positions, dtype=float)
        v = np.array(velocities, dtype=float)
        for body, motion in motions:
            r[body], v[body] = motion.at(t)
        r[free] = positions[free] + velocities[free] * t
        return r, v
    return at


# ------------------------------------------------------------------------------------------------
# openmm.app systems
# ------------------------------------------------------------------------------------------------

WATER_MODELS = {"tip3p": "amber14/tip3p.xml", "tip4pew": "amber14/tip4pew.xml"}


class Solvated:
    """A System from openmm.app with a minimised starting state (positions and velocities as numpy
    arrays in nm and nm/ps) that satisfies every constraint."""


def _prepare(topology, positions, system, seed, frozen=(), temperature=300.0, equilibrate=500):
    """Minimise (particles in frozen held fixed) and draw velocities; constraints hold to what the CPU
    platform's SETTLE gives (a few 1e-9 nm)."""
    minimise = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for index in frozen:
        minimise.setParticleMass(index, 0.0)
    integrator = openmm.VerletIntegrator(0.001)
    integrator.setConstraintTolerance(1e-10)
    context = openmm.Context(minimise, integrator, openmm.Platform.getPlatformByName("CPU"), {"DeterministicForces": "true"})
    context.setPositions(positions)
    context.applyConstraints(1e-10)
    openmm.LocalEnergyMinimizer.minimize(context, 5.0, 100)
    context.setVelocitiesToTemperature(temperature * unit.kelvin, seed)
    if equilibrate > 0:
        # Thermalise so that the NVE runs of the tests start near equilibrium (no relaxation
        # transient on top of the drift they measure).
        thermostat = openmm.LangevinMiddleIntegrator(temperature * unit.kelvin, 5.0 / unit.picosecond,
                                                     0.002 * unit.picosecond)
        thermostat.setRandomNumberSeed(seed)
        thermostat.setConstraintTolerance(1e-10)
        equilibration = openmm.Context(minimise, thermostat, openmm.Platform.getPlatformByName("CPU"),
                                       {"DeterministicForces": "true"})
        equilibration.setState(context.getState(getPositions=True, getVelocities=True))
        thermostat.step(equilibrate)
        context.setState(equilibration.getState(getPositions=True, getVelocities=True))
        context.applyConstraints(1e-10)
    context.applyVelocityConstraints(1e-10)
    state = context.getState(getPositions=True, getVelocities=True)
    result = Solvated()
    result.system = system
    result.topology = topology
    result.positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    result.velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    for index in frozen:
        result.velocities[index] = 0.0
    return result


def water_box(model="tip3p", size=1.7, seed=5, cutoff=0.7):
    """A cubic box (edge `size` nm) of rigid water, PME with a switched Lennard-Jones cutoff."""
    forcefield = app.ForceField("amber14-all.xml", WATER_MODELS[model])
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forcefield, model=model, boxSize=openmm.Vec3(size, size, size) * unit.nanometer)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.PME,
                                     nonbondedCutoff=cutoff * unit.nanometer, switchDistance=(cutoff - 0.1) * unit.nanometer,
                                     constraints=None, rigidWater=True, ewaldErrorTolerance=1e-4)
    return _prepare(modeller.topology, modeller.positions, system, seed)



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
    peptide = openmmrigid.testing.alanineDipeptide()
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
    _add_molecule(modeller, "BNZ", benzene, benzeneBonds, np.array([half + quarter] * 3), _random_rotation(rng))
    co2 = [("C", "C", [0.0, 0.0, 0.0]), ("O1", "O", [0.0, 0.0, 0.116]), ("O2", "O", [0.0, 0.0, -0.116])]
    _add_molecule(modeller, "CO2", co2, [(0, 1), (0, 2)], np.array([quarter, quarter, half + quarter]),
                  _random_rotation(rng))
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

def energy_drift(times, energies):
    """The least-squares slope of energies against times (kJ/mol/ps when times are in ps), its
    standard error, and the root-mean-square residual about the fitted line."""
    times = np.asarray(times, dtype=float)
    energies = np.asarray(energies, dtype=float)
    design = np.vstack([times, np.ones_like(times)]).T
    (slope, intercept), *_ = np.linalg.lstsq(design, energies, rcond=None)
    residual = energies - (slope * times + intercept)
    n = len(times)
    standardError = np.sqrt(residual @ residual / (n - 2) / np.sum((times - times.mean()) ** 2))
    return slope, standardError, np.sqrt(np.mean(residual ** 2))


def block_drift(times, energies, blocks):
    """The drift of energies against times from the means of `blocks` consecutive blocks: slope and
    standard error of the line through the block means. Block means are nearly independent when a
    block is longer than the correlation time of the energy fluctuations, so this standard error,
    unlike that of a fit to every sample, does not understate the uncertainty of the slope."""
    n = len(times) // blocks * blocks
    blockTimes = np.asarray(times[:n], dtype=float).reshape(blocks, -1).mean(axis=1)
    blockEnergies = np.asarray(energies[:n], dtype=float).reshape(blocks, -1).mean(axis=1)
    slope, standardError, _ = energy_drift(blockTimes, blockEnergies)
    return slope, standardError


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


def positions_of(context):
    return context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)


def velocities_of(context):
    return context.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(
        unit.nanometer / unit.picosecond)


# ------------------------------------------------------------------------------------------------
# Copies of an integrator, every way a user can make one
# ------------------------------------------------------------------------------------------------

COPY_METHODS = ["pickle", "copy", "deepcopy", "xml", "clone", "deserializeIntegrator"]


def copy_integrator(integrator, method):
    """A copy of the integrator made by `method`, one of COPY_METHODS."""
    import copy
    import pickle
    import openmmrigid
    if method == "pickle":
        return pickle.loads(pickle.dumps(integrator))
    if method == "copy":
        return copy.copy(integrator)
    if method == "deepcopy":
        return copy.deepcopy(integrator)
    if method == "xml":
        return openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(integrator))
    if method == "clone":
        return openmm.XmlSerializer.clone(integrator)
    if method == "deserializeIntegrator":
        return openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(integrator))
    raise ValueError(f"unknown copy method {method!r}; expected one of {COPY_METHODS}")
