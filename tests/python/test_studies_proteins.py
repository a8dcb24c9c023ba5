"""The analysis code of the protein studies (benchmarks/studies/protein_mts.py, xh_groups_model.py): the stock recipe's
CustomIntegrator against an independent r-RESPA and against BAOAB's exact harmonic sampling, the accurate-step rule,
the error over independent runs, the angle and dihedral geometry against OpenMM's own, and the solute's observables
(its temperature against a count by hand and the State's kinetic energy, the helical basin, the dihedrals' fluctuation,
their biases and columns)."""

import json
import pathlib
import sys

import numpy as np
import openmm
import pytest
from openmm import app, unit

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
pytest.importorskip("harness")
from studies import protein_mts, xh_groups_model  # noqa: E402

import openmmrigid  # noqa: E402
import rigidtesting  # noqa: E402
import setups  # noqa: E402
from harness import rigidDegreesOfFreedom  # noqa: E402

BOLTZMANN = protein_mts.BOLTZMANN


def oneParticleSystem(particles, mass, stiff, soft):
    """Independent particles (mass in amu) in a soft harmonic well (force group 0, k = soft) and a stiff quartic one
    (group 1, stiff/4 r^4 per coordinate)."""
    system = openmm.System()
    forces = [openmm.CustomExternalForce(f"0.5*{soft}*(x^2 + y^2 + z^2)"),
              openmm.CustomExternalForce(f"0.25*{stiff}*(x^4 + y^4 + z^4)")] if stiff else \
        [openmm.CustomExternalForce(f"0.5*{soft}*(x^2 + y^2 + z^2)")]
    for group, force in enumerate(forces):
        force.setForceGroup(group)
        system.addForce(force)
    for i in range(particles):
        system.addParticle(mass)
        for force in forces:
            force.addParticle(i, [])
    return system


def test_stock_recipe_is_r_respa_with_its_substeps():
    """Without friction the recipe is r-RESPA: the outer half kicks of group 0 around `substeps` velocity Verlet steps of
    group 1, the step split in equal substeps (an independent numpy integration of the same nonlinear forces)."""
    mass, soft, stiff, stepFs, substeps = 2.0, 300.0, 4.0e5, 6.0, 3
    integrator = protein_mts.stockRecipe(stepFs, substeps, friction=0.0)
    context = openmm.Context(oneParticleSystem(1, mass, stiff, soft), integrator, openmm.Platform.getPlatformByName("Reference"))
    x, v = np.array([[0.03, -0.05, 0.02]]), np.array([[1.2, 0.4, -0.8]])
    context.setPositions(x)
    context.setVelocities(v)
    integrator.step(5)
    state = context.getState(getPositions=True, getVelocities=True)
    dt, h = stepFs*1e-3, stepFs*1e-3/substeps
    slow, fast = (lambda x: -soft*x), (lambda x: -stiff*x**3)
    for _ in range(5):
        v = v + 0.5*dt*slow(x)/mass
        for _ in range(substeps):
            v = v + 0.5*h*fast(x)/mass
            x = x + h*v
            v = v + 0.5*h*fast(x)/mass
        v = v + 0.5*dt*slow(x)/mass
    assert np.allclose(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer), x, rtol=1e-9, atol=1e-12)
    assert np.allclose(state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond), v, rtol=1e-9, atol=1e-12)


def test_stock_recipe_samples_a_harmonic_well_as_baoab():
    """With no bonded forces and two substeps the recipe is BAOAB (the O stage at the midpoint of the step): for a harmonic
    well its positions sample <x^2> = kT/k exactly at any step, its on-step velocities <v^2> = kT/m (1 - (omega dt/2)^2)
    (Leimkuhler & Matthews 2013). At omega dt = 1 the second is 0.75 of kT/m; an O stage elsewhere would bias the first."""
    particles, mass, stepFs, temperature = 400, 1.0, 4.0, 300.0
    omega = 1/(stepFs*1e-3)
    kT, k = BOLTZMANN*temperature, mass*omega**2
    integrator = protein_mts.stockRecipe(stepFs, 2, temperature=temperature, friction=20.0)
    integrator.setRandomNumberSeed(3)
    context = openmm.Context(oneParticleSystem(particles, mass, 0.0, k), integrator, openmm.Platform.getPlatformByName("Reference"))
    rng = np.random.default_rng(5)
    context.setPositions(rng.normal(0.0, np.sqrt(kT/k), (particles, 3)))
    context.setVelocities(rng.normal(0.0, np.sqrt(kT/mass), (particles, 3)))
    integrator.step(100)
    squares = []
    for _ in range(150):
        integrator.step(10)
        state = context.getState(getPositions=True, getVelocities=True)
        squares.append([np.mean(state.getPositions(asNumpy=True)._value**2), np.mean(state.getVelocities(asNumpy=True)._value**2)])
    position, velocity = np.mean(squares, axis=0)
    assert position*k/kT == pytest.approx(1.0, abs=0.02)
    assert velocity*mass/kT == pytest.approx(1 - (omega*stepFs*1e-3/2)**2, abs=0.02)


def row(configuration, step, U, bonded, error=10.0):
    return dict(configuration=configuration, step=step, U_bias=U, U_bias_error=error, bonded_bias=bonded, bonded_bias_error=error)


def test_accurate_step_is_the_largest_up_to_which_every_step_passes():
    """A step passes with both biases within two combined errors; the accurate step is the last of an unbroken run from the
    smallest step (a pass after a failure does not count), None where the smallest fails; a failed run has no biases."""
    rows = [row("a", 6, 5.0, -19.0), row("a", 8, 21.0, 0.0), row("a", 10, 0.0, 0.0),
            row("b", 4, 0.0, 25.0), row("b", 6, 0.0, 0.0),
            row("c", 6, -20.0, 20.0), row("c", 8, 0.0, 0.0), dict(configuration="c", step=10, failed="unstable")]
    assert protein_mts.accurateSteps(rows) == {"a": 6, "b": None, "c": 8}


def test_accurate_steps_of_the_committed_summary_are_the_claim():
    """The rule read on the stored villin summary gives the claim's steps: 10 fs with rigid X-H groups and substeps, 8 fs for
    the stock recipe, 4 fs for stock HMR."""
    summary = json.loads((ROOT/"benchmarks"/"data"/"protein_mts.json").read_text())["summary"]
    steps = protein_mts.accurateSteps([r for r in summary["rows"] if r["system"] == "villin"])
    assert (steps["xh-mts"], steps["recipe"], steps["stock-hmr"]) == (10, 8, 4)


def test_over_seeds_is_the_spread_of_the_runs_means_or_one_runs_own_error():
    assert protein_mts.overSeeds([[1.0, 9.0], [3.0, 9.0], [5.0, 9.0]]) == pytest.approx((3.0, 2.0/np.sqrt(3)))
    assert protein_mts.overSeeds([[4.0, 0.5]]) == (4.0, 0.5)


def test_geometry_is_openmms_angle_and_dihedral():
    """Bond angles and dihedrals (with their sign) as OpenMM's CustomAngleForce and CustomTorsionForce compute theta."""
    rng = np.random.default_rng(2)
    x = rng.normal(size=(40, 3))
    triples, quads = rng.choice(40, size=(6, 3), replace=False), rng.choice(40, size=(6, 4), replace=False)
    system = openmm.System()
    for _ in range(40):
        system.addParticle(1.0)
    for group, indices in enumerate(list(triples) + list(quads)):
        force = openmm.CustomAngleForce("theta") if len(indices) == 3 else openmm.CustomTorsionForce("theta")
        force.addAngle(*indices, []) if len(indices) == 3 else force.addTorsion(*indices, [])
        force.setForceGroup(group)
        system.addForce(force)
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(x)
    theta = [np.degrees(context.getState(getEnergy=True, groups={g}).getPotentialEnergy()._value) for g in range(12)]
    assert np.allclose(xh_groups_model.geometry(x, triples), theta[:6], atol=1e-6)
    assert np.allclose(xh_groups_model.geometry(x, quads), theta[6:], atol=1e-6)


def test_angle_types_and_backbone_dihedrals_of_alanine_dipeptide():
    """Every bond angle of the force field's HarmonicAngleForce is typed once: three methyl groups give nine H-C-H angles,
    the two peptide groups two O-C-N; one residue has phi and psi."""
    pdb = rigidtesting.alanineDipeptide()
    system = app.ForceField("amber14-all.xml").createSystem(pdb.topology)
    angles = next(f for f in system.getForces() if isinstance(f, openmm.HarmonicAngleForce))
    expected = sorted(tuple(sorted([i, k]) + [j]) for i, j, k, *_ in (angles.getAngleParameters(n) for n in range(angles.getNumAngles())))
    types = xh_groups_model.angleTypes(pdb.topology)
    found = sorted(tuple(sorted([i, k]) + [j]) for triples in types.values() for i, j, k in triples)
    assert found == expected
    assert (len(types["H-C-H"]), len(types["O-C-N"]), len(types["N-CA-C"])) == (9, 2, 1) and "H-N-H" not in types
    phi, psi = xh_groups_model.backboneDihedrals(pdb.topology)
    names = [[atom.name for atom in pdb.topology.atoms()][i] for i in (*phi[0], *psi[0])]
    assert (phi.shape, psi.shape, names) == ((1, 4), (1, 4), ["C", "N", "CA", "C", "N", "CA", "C", "N"])


@pytest.mark.parametrize("rigid", [False, True])
def test_solute_degrees_of_freedom_by_hand_and_kinetic_energy_split_of_the_states(rigid):
    """The dipeptide's degrees of freedom counted by hand from the topology (stock, HBonds: 3 per atom less one per X-H bond;
    rigid X-H groups: 3 per heavy atom without hydrogens, 5 per X-H, 6 per XH2 or XH3), the waters' 6 each, the whole system's
    count less the CMMotionRemover's 3; and the solute's and the water's kinetic energies (rigid: in moments raised to 0.16)
    add up to the State's, which the integrator sums on its own."""
    built = protein_mts.dipeptide()
    protein = protein_mts.solute(built)
    hydrogens = {atom.index: 0 for atom in built.topology.atoms() if protein[atom.index] and atom.element.symbol != "H"}
    for bond in built.topology.bonds():
        heavy = [atom.index for atom in bond if atom.element.symbol != "H"]
        if len(heavy) == 1 and heavy[0] in hydrogens:
            hydrogens[heavy[0]] += 1
    byHand = sum({0: 3, 1: 5}.get(n, 6) for n in hydrogens.values()) if rigid else 3*protein.sum() - sum(hydrogens.values())
    assert (protein.sum(), byHand) == (22, 45 if rigid else 54)
    bodies = openmmrigid.rigidHydrogenGroups(built.topology, built.system) if rigid else None
    integrator = setups.makeIntegrator("rigid-langevin" if rigid else "stock-middle", 2.0, floor=0.16 if rigid else None, bodies=bodies)
    context = openmm.Context(built.system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(built.positions)
    context.setVelocitiesToTemperature(300.0, 1)
    integrator.step(2)
    (kinetic, dof), (waterKinetic, waterDof) = (protein_mts.soluteKinetic(context, integrator, inside) for inside in (protein, ~protein))
    whole = rigidDegreesOfFreedom(context, integrator) if rigid else rigidtesting.degreesOfFreedom(built.system)
    assert (dof, waterDof, whole) == (byHand, 6*216, byHand + 6*216 - 3)
    state = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
    assert kinetic(state) + waterKinetic(state) == pytest.approx(state.getKineticEnergy().value_in_unit(setups.KJ), rel=1e-6)
    assert 0.2*dof*BOLTZMANN*300 < 2*kinetic(state) < 5*dof*BOLTZMANN*300   # a temperature, not a sum over the box


def test_helical_basin_is_xh_groups_models_and_the_fluctuation_is_circular():
    """On a 1-degree grid of (phi, psi) the basin counts what xh_groups_model.analyse counts (any moved edge would differ); an
    ideal alpha helix is in it, beta, polyproline and left-handed helix are not. The fluctuation about a mean near +-180 deg is
    the spread of the unwrapped angles, as near 0, not the 180 deg a linear mean would give."""
    phi, psi = (grid.reshape(1, -1) for grid in np.meshgrid(np.arange(-180.0, 180.0), np.arange(-180.0, 180.0)))
    theirs = xh_groups_model.analyse({}, np.zeros((1, 0)), phi, psi, np.zeros((1, 4)))["quantities"][0]
    assert theirs[0] == "phi/psi: fraction alpha-helical" and theirs[2] == protein_mts.helical(phi, psi).mean()
    assert list(protein_mts.helical(np.array([-57.0, -120.0, -75.0, 57.0]), np.array([-47.0, 130.0, 145.0, 47.0]))) == [True, False, False, False]
    rng = np.random.default_rng(8)
    spread = rng.normal(0.0, [10.0, 25.0], (4000, 2))
    angles = (spread + [180.0, -40.0] + 180.0) % 360.0 - 180.0
    assert protein_mts.dihedralFluctuation(angles) == pytest.approx(spread.std(axis=0).mean(), rel=1e-3)
    assert protein_mts.dihedralFluctuation(angles[:, :1]) == pytest.approx(spread[:, 0].std(), rel=1e-3)


class TablePage:
    def section(self, title, text=""):
        pass

    def table(self, columns, rows):
        self.columns, self.rows = columns, rows


def test_biases_and_columns_of_the_solute_observables_only_where_runs_have_them():
    """Runs that measured T_solute, helix and dihedral_rms get their biases against the model's reference (errors combined, or
    none where a single run has no error) and three more columns, bold beyond two errors; runs from before (no such key) give
    the table of before."""
    def result(configuration, step, samples):
        return dict(job=dict(system="villin", configuration=configuration, step=step), samples=samples, failed=None, blocked=False)
    def sample(U, solute, helix, rms):
        return dict(U=[U, 5.0], T=[300.0, 0.5], bonded=[100.0, 2.0], T_solute=[solute, 1.0], helix=[helix, 0.01], dihedral_rms=[rms, None])
    results = [result("xh", 2, [sample(-10.0, 300.0, 0.5, 12.0), sample(-20.0, 302.0, 0.7, 14.0)]),
               result("xh-mts", 8, [sample(-12.0, 311.0, 0.7, 20.0), sample(-18.0, 313.0, 0.5, 20.0)]),
               result("xh-mts", 10, [sample(-15.0, 302.0, 0.6, 13.0)])]
    rows, ran = protein_mts.biasRows(results)
    eight = ran["villin", "xh-mts", 8]
    assert (eight["T_solute_bias"], eight["helix_bias"], eight["dihedral_rms_bias"]) == pytest.approx((11.0, 0.0, 7.0))
    assert (eight["T_solute_bias_error"], eight["dihedral_rms_bias_error"]) == pytest.approx((np.sqrt(2.0), 1.0))
    assert ran["villin", "xh-mts", 10]["T_solute_bias_error"] == pytest.approx(np.hypot(1.0, 1.0))
    assert ran["villin", "xh-mts", 10]["dihedral_rms_bias_error"] is None
    page = TablePage()
    protein_mts.section(page, "", "", rows)
    assert page.columns[5:8] == ["T solute bias (K)", "helix bias", "dihedral rms bias (deg)"] and len(page.columns) == 12
    assert page.rows[1][5:8] == ["**+11.0 ± 1.4**", "+0.000 ± 0.141", "**+7.0 ± 1.0**"] and page.rows[2][7] == "+0.0"
    old = [dict(r, samples=[{k: s[k] for k in ("U", "T", "bonded")} for s in r["samples"]]) for r in results]
    protein_mts.section(page, "", "", protein_mts.biasRows(old)[0])
    assert len(page.columns) == 9 and "T (K)" in page.columns and not any("solute" in c for c in page.columns)
