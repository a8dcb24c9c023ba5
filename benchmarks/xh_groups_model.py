#!/usr/bin/env python
"""Rigid X-H groups as a model change: villin HP35 in water with flexible H-X-H angles (stock
LangevinMiddleIntegrator) against the same System with openmmrigid.rigidHydrogenGroups' bodies, with
and without planar groups.

System: villin headpiece HP35 from openmm's app/data/test.pdb, its water and ion removed and
re-solvated with Modeller (amber14-all.xml + amber14/tip3p.xml, padding `--padding` nm, neutralized),
PME with a 0.9 nm cutoff, constraints=HBonds, rigidWater=True; energy minimized once (tolerance 10
kJ/mol/nm) with those constraints. From the minimum, `--pre-equilibrate` ps of the flexible model
(LangevinMiddleIntegrator, velocities drawn at 310 K) relax the water; every run starts from that
state with velocities drawn again at 310 K (seed 1), the rigid runs with each body's atoms put back
in its minimized shape (superimposed, mass-weighted, on where the body is), so that the bodies
freeze the minimum's internal geometry rather than a thermal snapshot's.

Runs (310 K, friction 1/ps, step `--step` fs, CPU platform with `--threads` threads):

- flexible: openmm.LangevinMiddleIntegrator: X-H bonds constrained, H-X-H angles flexible;
- xh-rigid: openmmrigid.RigidBodyLangevinIntegrator with bodies = rigidHydrogenGroups(topology,
  system): every X-H group and water one rigid body (H-X-H angles frozen at the minimum's), the System
  after removeIntraBodyInteractions;
- xh-planar: the same with planarGroups=True (aromatic rings, ASN/GLN amides and peptide groups C O N
  H rigid too).

Each run: `--equilibrate` ps, then `--production` ps saving a frame every `--save-every` fs. Per
frame, over the solute: the bond angles by type (backbone types by atom names, heavy-atom angles
inside aromatic rings, other heavy-atom angles, H-X-H and heavy-X-H), backbone phi and psi, the
solute's temperature (its kinetic energy over its degrees of freedom: 3 per atom less one per
constraint for flexible, 3 + 3 (2 for a linear body) per body and 3 per free atom for the rigid runs;
velocities as the integrators hold them, half a step behind the positions), and the energy terms of
the ORIGINAL System (HarmonicBondForce, HarmonicAngleForce, PeriodicTorsionForce by force group, and
the total potential energy of the box) evaluated on the frame, so that all three runs are measured
with one Hamiltonian (the terms removed inside bodies are constants of the bodies' shapes). Errors
are the standard errors of the means from block averages (benchmarking.blockMean: the larger of the
5- and 10-block estimates); a difference is marked where it exceeds three combined standard errors.
The rms fluctuation of an angle type is that of each instance about its own mean over the run
(zero for an angle a body freezes), the root of the mean square over instances.

    python benchmarks/xh_groups_model.py                      # defaults: about 15 min on 2 cores
    python benchmarks/xh_groups_model.py --production 200     # a longer run
    python benchmarks/xh_groups_model.py --quick              # a smoke check (benchmarks/results/)
    python benchmarks/xh_groups_model.py --from-saved         # the report again from the saved frames

The measurements of each run are saved in benchmarks/results/xh_groups_model.npz (git ignores it);
the results document is docs/results/xh_groups_model.md, whose section "Reading", written by hand,
is carried over when the document is written again (check it against the new numbers).
"""

import argparse
import os
import time
import warnings

import numpy as np
import openmm
from openmm import app, unit

import benchmarking
import openmmrigid
from benchmarking import say, stamp
import rigidtesting

NAME = "xh_groups_model"
RUNS = ("flexible", "xh-rigid", "xh-planar")
TEMPERATURE = 310.0
R = rigidtesting.MOLAR_GAS_CONSTANT
RINGS = {"PHE": "CG CD1 CD2 CE1 CE2 CZ", "TYR": "CG CD1 CD2 CE1 CE2 CZ",
         "TRP": "CG CD1 CD2 NE1 CE2 CE3 CZ2 CZ3 CH2", "HIS": "CG ND1 CD2 CE1 NE2", "HID": "CG ND1 CD2 CE1 NE2",
         "HIE": "CG ND1 CD2 CE1 NE2", "HIP": "CG ND1 CD2 CE1 NE2"}
# Backbone angle types: (atom names, residue offsets relative to the central atom's residue).
BACKBONE = {"N-CA-C": (("N", "CA", "C"), (0, 0, 0)), "CA-C-N": (("CA", "C", "N"), (0, 0, 1)),
            "C-N-CA": (("C", "N", "CA"), (-1, 0, 0)), "CA-C-O": (("CA", "C", "O"), (0, 0, 0)),
            "O-C-N": (("O", "C", "N"), (0, 0, 1)), "N-CA-CB": (("N", "CA", "CB"), (0, 0, 0)),
            "CB-CA-C": (("CB", "CA", "C"), (0, 0, 0))}
SETTINGS = ("step", "pre_equilibrate", "equilibrate", "production", "save_every", "padding", "floor", "platform", "threads")
ENERGY_GROUPS = {"HarmonicBondForce": 1, "HarmonicAngleForce": 2, "PeriodicTorsionForce": 3}


# ---------------------------------------------------------------------------------------------------
# The system and what is measured on it

def buildSystem(padding):
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.delete([residue for residue in modeller.topology.residues() if residue.name in ("HOH", "Cl")])
    modeller.addSolvent(forceField, model="tip3p", padding=padding*unit.nanometer, neutralize=True)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True)
    for force in system.getForces():
        force.setForceGroup(ENERGY_GROUPS.get(type(force).__name__, 0))
    return modeller.topology, modeller.positions, system


def isHydrogen(atom):
    return atom.element is not None and atom.element.symbol == "H"


def angleTypes(topology, solute):
    """{type: array of (i, j, k)} for every bond angle of the solute, from the topology's bonds."""
    neighbours = {}
    for a, b in topology.bonds():
        if a.index in solute and b.index in solute:
            neighbours.setdefault(a.index, []).append(b)
            neighbours.setdefault(b.index, []).append(a)
    atoms = list(topology.atoms())
    residues = list(topology.residues())
    inRing = {atom.index for residue in residues if residue.name in RINGS
              for atom in residue.atoms() if atom.name in RINGS[residue.name].split()}

    def backboneType(a, b, c):
        for name, (names, offsets) in BACKBONE.items():
            for first, last in ((a, c), (c, a)):
                if ((first.name, b.name, last.name) == names
                        and (first.residue.index - b.residue.index, 0, last.residue.index - b.residue.index) == offsets):
                    return name, (first, b, last)
        return None, None

    types = {}
    for centre in sorted(neighbours):
        b = atoms[centre]
        bonded = neighbours[centre]
        for x in range(len(bonded)):
            for y in range(x + 1, len(bonded)):
                a, c = bonded[x], bonded[y]
                hydrogens = isHydrogen(a) + isHydrogen(c)
                if hydrogens == 2:
                    name, triple = f"H-{b.element.symbol}-H", (a, b, c)
                elif hydrogens == 1:
                    name, triple = f"heavy-{b.element.symbol}-H", (a, b, c)
                else:
                    name, triple = backboneType(a, b, c)
                    if name is None:
                        ring = {a.index, b.index, c.index} <= inRing and a.residue is b.residue is c.residue
                        name, triple = ("ring (heavy)" if ring else "other heavy"), (a, b, c)
                types.setdefault(name, []).append([atom.index for atom in triple])
    order = list(BACKBONE) + ["ring (heavy)", "other heavy"]
    rank = {name: number for number, name in enumerate(order)}
    names = sorted(types, key=lambda name: (rank.get(name, len(order) + name.startswith("H-")), name))
    return {name: np.array(types[name]) for name in names}


def backboneDihedrals(topology):
    """(phi quadruples, psi quadruples, the residues) for the residues that have both neighbours in the chain."""
    phi, psi, used = [], [], []
    residues = [residue for residue in topology.residues() if residue.name not in ("HOH", "NA", "CL", "Na+", "Cl-")]
    names = [{atom.name: atom.index for atom in residue.atoms()} for residue in residues]
    for i in range(1, len(residues) - 1):
        before, here, after = names[i - 1], names[i], names[i + 1]
        if all(key in d for d, key in ((before, "C"), (here, "N"), (here, "CA"), (here, "C"), (after, "N"))):
            phi.append([before["C"], here["N"], here["CA"], here["C"]])
            used.append(residues[i])
            psi.append([here["N"], here["CA"], here["C"], after["N"]])
    return np.array(phi), np.array(psi), used


def angles(x, triples):
    u, v = x[triples[:, 0]] - x[triples[:, 1]], x[triples[:, 2]] - x[triples[:, 1]]
    cosine = np.sum(u*v, axis=1)/np.linalg.norm(u, axis=1)/np.linalg.norm(v, axis=1)
    return np.degrees(np.arccos(np.clip(cosine, -1, 1)))


def dihedrals(x, quads):
    b0, b1, b2 = x[quads[:, 0]] - x[quads[:, 1]], x[quads[:, 2]] - x[quads[:, 1]], x[quads[:, 3]] - x[quads[:, 2]]
    b1n = b1/np.linalg.norm(b1, axis=1)[:, None]
    v = b0 - np.sum(b0*b1n, axis=1)[:, None]*b1n
    w = b2 - np.sum(b2*b1n, axis=1)[:, None]*b1n
    return np.degrees(np.arctan2(np.sum(np.cross(b1n, v)*w, axis=1), np.sum(v*w, axis=1)))


# ---------------------------------------------------------------------------------------------------
# The runs

def makeIntegrator(run, topology, system, args):
    """(integrator, System to run, bodies or None)."""
    if run == "flexible":
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, 1/unit.picosecond,
                                                     args.step*unit.femtoseconds)
        return integrator, system, None
    bodies = openmmrigid.rigidHydrogenGroups(topology, system, planarGroups=(run == "xh-planar"))
    integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE*unit.kelvin, 1/unit.picosecond,
                                                         args.step*unit.femtoseconds, bodies)
    if args.floor:
        integrator.setMinimumMomentOfInertia(args.floor)
    return integrator, openmmrigid.removeIntraBodyInteractions(system, bodies), bodies


def soluteDegreesOfFreedom(run, system, bodies, solute, positions):
    """The solute's degrees of freedom: 3 per atom less its constraints, or with bodies 3 per atom in no
    body plus 3 + 0 (point), 2 (linear) or 3 per body (benchmarking.bodyKind, from `positions`, nm)."""
    if bodies is None:
        constraints = sum(1 for k in range(system.getNumConstraints())
                          if system.getConstraintParameters(k)[0] in solute)
        return 3*len(solute) - constraints
    inBodies = set()
    dof = 0
    for body in bodies:
        if body[0] in solute:
            inBodies.update(body)
            masses = [system.getParticleMass(i).value_in_unit(unit.dalton) for i in body]
            kind = benchmarking.bodyKind(masses, np.asarray(positions)[list(body)])
            dof += 3 + {"point": 0, "linear": 2}.get(kind, 3)
    return dof + 3*len(set(solute) - inBodies)


def preEquilibrate(system, minimum, args, platform, properties):
    """The shared start: `--pre-equilibrate` ps of the flexible model from the minimum (positions, nm)."""
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, 1/unit.picosecond, args.step*unit.femtoseconds)
    integrator.setRandomNumberSeed(7)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(minimum)
    context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 1)
    integrator.step(int(round(args.pre_equilibrate*1000/args.step)))
    return context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)


def reshaped(positions, minimum, bodies, masses):
    """positions with each body's atoms replaced by its minimized shape, superimposed (mass-weighted, same
    centre of mass) on where the body is: the bodies keep the minimum's internal geometry."""
    x = np.array(positions)
    for body in bodies:
        m, shape, where = masses[body], minimum[body], x[body]
        centreShape, centreWhere = m @ shape/m.sum(), m @ where/m.sum()
        u, _, vt = np.linalg.svd(((shape - centreShape)*m[:, None]).T @ (where - centreWhere))
        d = np.sign(np.linalg.det(vt.T @ u.T))
        rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
        x[body] = (shape - centreShape) @ rotation.T + centreWhere
    return x


def runOne(run, topology, start, minimum, system, analysis, measure, args, platform, properties):
    integrator, running, bodies = makeIntegrator(run, topology, system, args)
    integrator.setRandomNumberSeed(11)
    context = openmm.Context(running, integrator, platform, properties)
    if bodies:
        masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
        start = reshaped(start, minimum, bodies, masses)
    context.setPositions(start)
    context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 1)
    solute = measure["solute"]
    dof = soluteDegreesOfFreedom(run, system, bodies, set(solute.tolist()), start)
    masses = np.array([system.getParticleMass(int(i)).value_in_unit(unit.dalton) for i in solute])
    every = max(1, int(round(args.save_every/args.step)))
    frames = int(round(args.production*1000/args.step))//every
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        integrator.step(int(round(args.equilibrate*1000/args.step)))
        stamp(f"{run}: equilibrated {args.equilibrate:g} ps; {frames} frames every {every*args.step:g} fs")
        progress = benchmarking.Progress(run, frames)
        series = {key: [] for key in ("angles", "phi", "psi", "T", "energies")}
        for frame in range(frames):
            integrator.step(every)
            state = context.getState(getPositions=True, getVelocities=True)
            x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)[solute]
            series["angles"].append(np.concatenate([angles(x, triples) for triples in measure["angles"].values()]))
            series["phi"].append(dihedrals(x, measure["phi"]))
            series["psi"].append(dihedrals(x, measure["psi"]))
            series["T"].append(np.sum(masses[:, None]*v**2)/(dof*R))
            analysis.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
            analysis.setPositions(x)
            series["energies"].append(
                [analysis.getState(getEnergy=True, groups={group}).getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
                 for group in ENERGY_GROUPS.values()]
                + [analysis.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)])
            progress.update(frame + 1)
    elapsed = time.perf_counter() - started
    accuracy = sorted({str(w.message).split(";")[0] for w in caught if issubclass(w.category, Warning)})
    steps = int(round((args.equilibrate + args.production)*1000/args.step))
    stamp(f"{run}: {steps} steps in {elapsed:.0f} s ({steps/elapsed:.1f} steps/s); solute dof {dof}"
          + (f"; {len(bodies)} bodies" if bodies else ""))
    result = {key: np.array(value) for key, value in series.items()}
    result["angle_types"] = list(measure["angles"])  # the order of the angle columns
    result["dof"] = dof
    result["bodies"] = len(bodies) if bodies else 0
    result["warnings"] = "; ".join(accuracy)
    result["steps_per_second"] = steps/elapsed
    return result


# ---------------------------------------------------------------------------------------------------
# The report

def circularDifference(a, b):
    return (a - b + 180) % 360 - 180


def quantities(result, measure):
    """[(label, per-frame series, unit, kind)]: kind 'mean' (report the block mean) or 'std' (a variance series)."""
    rows = []
    offset = 0
    for name, triples in measure["angles"].items():
        values = result["angles"][:, offset:offset + len(triples)]
        offset += len(triples)
        rows.append((f"angle {name} ({len(triples)}): mean", values.mean(axis=1), "deg", "mean"))
        rows.append((f"angle {name}: rms fluctuation", np.mean((values - values.mean(axis=0))**2, axis=1), "deg", "std"))
    phi, psi = result["phi"], result["psi"]
    helical = (phi > -160) & (phi < -20) & (psi > -120) & (psi < 50)
    rows.append(("phi/psi: fraction alpha-helical", helical.mean(axis=1), "", "mean"))
    rows.append(("phi: rms change from the minimum", np.mean(circularDifference(phi, measure["phi0"])**2, axis=1), "deg", "std"))
    rows.append(("psi: rms change from the minimum", np.mean(circularDifference(psi, measure["psi0"])**2, axis=1), "deg", "std"))
    for column, name in enumerate(list(ENERGY_GROUPS) + ["U (whole box)"]):
        rows.append((f"{name}", result["energies"][:, column], "kJ/mol", "mean"))
    energies = result["energies"]
    rows.append(("U less the three bonded terms", energies[:, 3] - energies[:, :3].sum(axis=1), "kJ/mol", "mean"))
    rows.append(("solute temperature", result["T"], "K", "mean"))
    return rows


def estimate(series, kind):
    mean, error = benchmarking.blockMean(series)
    if kind == "std":  # a mean square: its root, and the error propagated
        root = np.sqrt(mean)
        return root, error/(2*root) if root > 0 else 0.0
    return mean, error


def report(results, measure, args, document):
    table = {run: [(label, estimate(series, kind), units) for label, series, units, kind
                   in quantities(results[run], measure)] for run in results}
    labels = [label for label, _, _ in table["flexible"]]
    measure["energy_rows"] = [labels.index("HarmonicBondForce"), labels.index("HarmonicAngleForce")]
    columns = ["quantity", "unit"] + [run for run in RUNS if run in results] + \
              [f"{run} - flexible (sigma)" for run in RUNS[1:] if run in results]
    rows = []
    for number, (label, _, units) in enumerate(table["flexible"]):
        row = [label, units]
        for run in RUNS:
            if run in results:
                value, error = table[run][number][1]
                digits = 4 if abs(value) < 1 else 2 if abs(value) < 1000 else 1
                row.append(f"{value:.{digits}f} ± {error:.{digits}f}")
        base, baseError = table["flexible"][number][1]
        for run in RUNS[1:]:
            if run in results:
                value, error = table[run][number][1]
                combined = np.hypot(error, baseError)
                if combined == 0:  # a quantity that did not change along either run
                    row.append("0 (constant)" if value == base else "**differs (constant)**")
                    continue
                sigma = (value - base)/combined
                row.append(f"**{sigma:+.1f}**" if abs(sigma) > 3 else f"{sigma:+.1f}")
        rows.append(row)
    say("\n".join(benchmarking.markdownTable(columns, rows)))
    document.section("Results", f"{len(results['flexible']['T'])} frames per run, every {args.save_every:g} fs, "
                                f"after {args.pre_equilibrate:g} ps (shared) + {args.equilibrate:g} ps; mean ± standard error (block averages). "
                                "Angle types: the number of instances in brackets; mean over instances and frames; rms fluctuation: "
                                "of each instance about its own mean over the run, the root of the mean square over "
                                "instances (0 for an angle a body freezes). "
                                "Last columns: the difference from flexible over the combined standard error "
                                "(bold where above 3).")
    document.table(columns, rows)
    document.section("The bonded energy that the bodies freeze",
                     "Each harmonic term whose atoms all lie in one body is frozen at its value in the minimized "
                     "structure, where the flexible run gives it a thermal energy of about kT/2 (equipartition, "
                     f"kT = {R*TEMPERATURE:.3f} kJ/mol): the expected shift of the term's mean energy is about "
                     "-n kT/2 (the energy of the frozen terms at the minimum, E0, is in both runs' values and "
                     "cancels to first order).")
    frozenRows = []
    for run in RUNS[1:]:
        if run not in results:
            continue
        for column, (force, count, energy) in enumerate(frozenTerms(measure, run)):
            value, error = table[run][measure["energy_rows"][column]][1]
            base, baseError = table["flexible"][measure["energy_rows"][column]][1]
            frozenRows.append([run, force, count, f"{energy:.1f}", f"{-count*R*TEMPERATURE/2:.1f}",
                               f"{value - base:.1f} ± {np.hypot(error, baseError):.1f}"])
    document.table(["run", "force", "frozen terms n", "E0 (kJ/mol)", "-n kT/2 (kJ/mol)", "measured shift (kJ/mol)"],
                   frozenRows)
    say("\n".join(benchmarking.markdownTable(["run", "force", "n", "E0", "-n kT/2", "measured shift"], frozenRows)))
    lines = []
    labels = [f"{residue.name}{residue.id}" for residue in measure["dihedral_residues"]]
    for run in results:
        for angle in ("phi", "psi"):
            change = np.sqrt(np.mean(circularDifference(results[run][angle], measure[f"{angle}0"])**2, axis=0))
            worst = np.argsort(change)[::-1][:2]
            lines.append(f"- {run}, {angle}: median over residues {np.median(change):.1f} deg; largest "
                         + ", ".join(f"{labels[i]} {change[i]:.0f} deg" for i in worst))
    document.section("Backbone dihedrals per residue",
                     "The rms change of phi and psi from the minimized structure, per residue (each residue's "
                     "over the run), its median over residues and the two largest:\n\n" + "\n".join(lines))
    say("\n".join(lines))
    document.section("Runs")
    runRows = [[run, results[run]["bodies"] or "-", results[run]["dof"], f"{results[run]['steps_per_second']:.1f}",
                results[run]["warnings"] or "none"] for run in RUNS if run in results]
    document.table(["run", "bodies", "solute dof", "steps/s (with the per-frame analysis)", "warnings"], runRows)
    return table


def frozenTerms(measure, run):
    """[(force, number of its terms inside one body, their energy at the minimum)] for HarmonicBondForce and
    HarmonicAngleForce with the bodies of this run."""
    topology, system, x = measure["topology"], measure["system"], measure["minimum"]
    bodies = openmmrigid.rigidHydrogenGroups(topology, system, planarGroups=(run == "xh-planar"))
    bodyOf = {index: number for number, body in enumerate(bodies) for index in body}

    def inside(particles):
        return particles[0] in bodyOf and all(bodyOf.get(p) == bodyOf[particles[0]] for p in particles)

    found = []
    for force in system.getForces():
        if isinstance(force, openmm.HarmonicBondForce):
            count, energy = 0, 0.0
            for term in range(force.getNumBonds()):
                i, j, length, k = force.getBondParameters(term)
                if inside((i, j)):
                    r = np.linalg.norm(x[i] - x[j])
                    count, energy = count + 1, energy + 0.5*k.value_in_unit(unit.kilojoule_per_mole/unit.nanometer**2)*(
                        r - length.value_in_unit(unit.nanometer))**2
            found.append(("HarmonicBondForce", count, energy))
    for force in system.getForces():
        if isinstance(force, openmm.HarmonicAngleForce):
            count, energy = 0, 0.0
            for term in range(force.getNumAngles()):
                i, j, k, theta0, stiffness = force.getAngleParameters(term)
                if inside((i, j, k)):
                    theta = np.radians(angles(x, np.array([[i, j, k]]))[0])
                    count, energy = count + 1, energy + 0.5*stiffness.value_in_unit(unit.kilojoule_per_mole/unit.radian**2)*(
                        theta - theta0.value_in_unit(unit.radian))**2
            found.append(("HarmonicAngleForce", count, energy))
    return found


def plots(results, measure, document):
    plt = benchmarking.pyplot()
    colours = {"flexible": "black", "xh-rigid": "tab:blue", "xh-planar": "tab:orange"}
    shown = ["N-CA-C", "CA-C-N", "C-N-CA", "O-C-N", "ring (heavy)", "H-C-H", "heavy-C-H", "heavy-N-H"]
    shown = [name for name in shown if name in measure["angles"]]
    figure, axes = plt.subplots(2, (len(shown) + 1)//2, figsize=(3.2*((len(shown) + 1)//2), 6))
    offsets, offset = {}, 0
    for name, triples in measure["angles"].items():
        offsets[name] = (offset, offset + len(triples))
        offset += len(triples)
    for axis, name in zip(axes.ravel(), shown):
        start, stop = offsets[name]
        for run, result in results.items():
            values = result["angles"][:, start:stop].ravel()
            axis.hist(values, bins=60, density=True, histtype="step", color=colours[run], label=run)
        axis.set_title(name, fontsize=9)
        axis.set_xlabel("angle (deg)", fontsize=8)
    axes.ravel()[0].legend(fontsize=7)
    path = document.figurePath(f"{NAME}_angles.png")
    benchmarking.saveFigure(figure, path)
    document.figure(path, "bond angle distributions by type")

    figure, axes = plt.subplots(1, 3, figsize=(13, 4))
    for run, result in results.items():
        axes[0].hist(result["phi"].ravel(), bins=72, range=(-180, 180), density=True, histtype="step",
                     color=colours[run], label=run)
        axes[1].hist(result["psi"].ravel(), bins=72, range=(-180, 180), density=True, histtype="step",
                     color=colours[run], label=run)
        axes[2].scatter(result["phi"].ravel(), result["psi"].ravel(), s=1, alpha=0.2, color=colours[run], label=run)
    for axis, label in zip(axes, ("phi (deg)", "psi (deg)", "phi (deg)")):
        axis.set_xlabel(label)
        axis.set_xlim(-180, 180)
    axes[2].set_ylim(-180, 180)
    axes[2].set_ylabel("psi (deg)")
    axes[0].legend(fontsize=8)
    path = document.figurePath(f"{NAME}_phipsi.png")
    benchmarking.saveFigure(figure, path)
    document.figure(path, "backbone phi and psi")

    figure, axes = plt.subplots(1, 5, figsize=(17, 3.4))
    labels = list(ENERGY_GROUPS) + ["U (whole box)"]
    for run, result in results.items():
        time = np.arange(1, len(result["T"]) + 1)*result["frame_ps"]
        for column in range(4):
            axes[column].plot(time, result["energies"][:, column], color=colours[run], lw=0.7, label=run)
        axes[4].plot(time, result["T"], color=colours[run], lw=0.7, label=run)
    for axis, label in zip(axes, labels + ["solute temperature (K)"]):
        axis.set_title(label, fontsize=9)
        axis.set_xlabel("time after equilibration (ps)", fontsize=8)
    axes[0].legend(fontsize=7)
    path = document.figurePath(f"{NAME}_energies.png")
    benchmarking.saveFigure(figure, path)
    document.figure(path, "energy terms of the original System and solute temperature along the runs")


def carriedReading(path):
    """The hand-written section '## Reading' of an earlier document, if any."""
    if not path.exists():
        return None
    text = path.read_text()
    marker = "\n## Reading"
    return text[text.index(marker) + 1:].rstrip() if marker in text else None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="0.2 ps, then 0.2 ps + 1 ps per run: a smoke check")
    parser.add_argument("--runs", nargs="+", default=list(RUNS), choices=RUNS)
    parser.add_argument("--step", type=float, default=2.0, help="step in fs (default 2)")
    parser.add_argument("--pre-equilibrate", type=float, default=8.0,
                        help="ps of the flexible model from the minimum, shared by every run (default 8)")
    parser.add_argument("--equilibrate", type=float, default=1.0, help="ps of each run before its first frame (default 1)")
    parser.add_argument("--production", type=float, default=18.0, help="ps of frames per run (default 18)")
    parser.add_argument("--save-every", type=float, default=50.0, help="fs between frames (default 50)")
    parser.add_argument("--padding", type=float, default=1.0, help="solvent padding in nm (default 1.0)")
    parser.add_argument("--floor", type=float, default=0.0,
                        help="setMinimumMomentOfInertia for the rigid runs, amu nm^2 (default 0: real moments)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, default=1, help="CPU threads (default 1)")
    parser.add_argument("--from-saved", action="store_true",
                        help="run nothing: the report from benchmarks/results/xh_groups_model.npz")
    args = parser.parse_args()
    if args.quick:
        args.pre_equilibrate, args.equilibrate, args.production = 0.2, 0.2, 1.0
    if "flexible" not in args.runs:
        parser.error("the flexible run is the reference: keep it in --runs")
    title = "Rigid X-H groups: the model change, measured"
    platform, properties, document = benchmarking.openRun(NAME, title, args)
    reading = carriedReading(document.path)
    saved = benchmarking.RESULTS/f"{NAME}{'_quick' if args.quick else ''}.npz"
    if args.from_saved:  # the provenance of the run that made the frames
        data = np.load(saved, allow_pickle=True)
        provenance = list(data["provenance"]) + [f"report written again from its saved frames by "
                                                 f"`{benchmarking.command()}`"]
        document = benchmarking.ResultsDocument(NAME, title, quick=args.quick, provenance=provenance,
                                                about=f"Method: the docstring of `benchmarks/{NAME}.py`.")
        for key, value in (data["settings"].item() if "settings" in data else {}).items():
            setattr(args, key, value)

    provenance = benchmarking.header(args.platform, args.threads)  # as the run starts
    stamp("building villin HP35 in TIP3P")
    topology, positions, system = buildSystem(args.padding)
    solute = np.array([atom.index for atom in topology.atoms() if atom.residue.name not in ("HOH", "NA", "CL")])
    analysis = openmm.Context(system, openmm.VerletIntegrator(0.001), platform, properties)
    say(f"{topology.getNumAtoms()} atoms, {len(solute)} in the solute, {topology.getNumResidues()} residues, "
        f"{system.getNumConstraints()} constraints")
    measure = {"solute": solute, "angles": angleTypes(topology, set(solute.tolist()))}
    measure["phi"], measure["psi"], measure["dihedral_residues"] = backboneDihedrals(topology)
    measure["topology"], measure["system"] = topology, system

    results = {}
    if args.from_saved:
        results = data["results"].item()
        minimum = data["minimum"]
        order = results["flexible"].get("angle_types", list(measure["angles"]))
        measure["angles"] = {name: measure["angles"][name] for name in order}
    else:
        stamp("minimizing")
        analysis.setPositions(positions)
        openmm.LocalEnergyMinimizer.minimize(analysis, 10.0, 0)
        minimum = analysis.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        stamp(f"equilibrating the flexible model {args.pre_equilibrate:g} ps: the start of every run")
        start = preEquilibrate(system, minimum, args, platform, properties)
        for run in args.runs:
            results[run] = runOne(run, topology, start, minimum, system, analysis, measure, args, platform, properties)
            results[run]["frame_ps"] = args.save_every/1000
        np.savez(saved, results=np.array(results, dtype=object), minimum=minimum,
                 provenance=np.array(provenance),
                 settings=np.array({key: getattr(args, key) for key in SETTINGS}, dtype=object))
        say(f"wrote {saved.relative_to(benchmarking.ROOT)}")
    measure["minimum"] = minimum
    measure["phi0"], measure["psi0"] = dihedrals(minimum, measure["phi"]), dihedrals(minimum, measure["psi"])

    report(results, measure, args, document)
    plots(results, measure, document)
    if reading:
        document.text(reading)
    document.write()


if __name__ == "__main__":
    main()
