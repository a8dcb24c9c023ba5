"""Rigid X-H groups as a model change: the flexible model against openmmrigid.rigidHydrogenGroups' bodies, with one Hamiltonian."""
import numpy as np, openmm
import openmmrigid, setups
from harness import Study, blockMean, pyplot
from studies.protein_mts import STARTS, build, helical, overSeeds
from setups import BOLTZMANN, KJ

TEMPERATURE, EDGES, RAMA = 310.0, np.linspace(80.0, 140.0, 41), np.linspace(-180.0, 180.0, 25)   # K; histogram bins (deg)
FULL = dict(equilibrate_ps=3.0, production_ps=18.0, every_fs=50.0, iterations=0)   # iterations: the minimizer's (0: to convergence)
QUICK = dict(equilibrate_ps=0.1, production_ps=0.4, every_fs=10.0, iterations=200)
TERMS = {"HarmonicBondForce": 1, "HarmonicAngleForce": 2, "PeriodicTorsionForce": 3}   # force groups of the analysis
BACKBONE = ["N-CA-C", "CA-C-N", "C-N-CA", "CA-C-O", "O-C-N", "N-CA-CB", "CB-CA-C"]
AROMATIC, RING = {"PHE", "TYR", "TRP", "HIS", "HID", "HIE", "HIP"}, set("CG CD1 CD2 CE1 CE2 CZ NE1 CE3 CZ2 CZ3 CH2 ND1 NE2".split())

def angleTypes(topology):
    """{type: (n, 3) atom indices} of the solute's bond angles: backbone (by names), in an aromatic ring, other heavy, heavy-X-H, H-X-H."""
    bonded, types, order = {}, {}, BACKBONE + ["ring (heavy)", "other heavy"]
    for a, b in (pair for bond in topology.bonds() if bond[0].residue.name != "HOH" for pair in (bond, bond[::-1])):
        bonded.setdefault(a, []).append(b)
    for b, a, c in ((b, a, c) for b, near in bonded.items() for k, a in enumerate(near) for c in near[k + 1:]):
        hydrogens = sum(atom.element.symbol == "H" for atom in (a, c))
        name = next((n for n in ("-".join(t.name for t in q) for q in ((a, b, c), (c, b, a))) if n in BACKBONE), None)
        ring = b.residue.name in AROMATIC and all(t.residue == b.residue and t.name in RING for t in (a, b, c))
        if hydrogens or not name:
            name = ["ring (heavy)" if ring else "other heavy", f"heavy-{b.element.symbol}-H", f"H-{b.element.symbol}-H"][hydrogens]
        types.setdefault(name, []).append([a.index, b.index, c.index])
    return {n: np.array(types[n]) for n in sorted(types, key=lambda n: (order.index(n) if n in order else 9 + n.startswith("H-"), n))}

def backboneDihedrals(topology):
    """The (n, 4) atom indices of phi and of psi, for each residue with a C before it and an N after it."""
    names = [{atom.name: atom.index for atom in residue.atoms()} for residue in topology.residues() if residue.name != "HOH"]
    return [np.array([[[p["C"], h["N"], h["CA"], h["C"]], [h["N"], h["CA"], h["C"], n["N"]]][k] for p, h, n in zip(names, names[1:], names[2:])
                      if "C" in p and {"N", "CA", "C"} <= h.keys() and "N" in n]) for k in (0, 1)]

def geometry(x, atoms):
    """Bond angles of (n, 3) or dihedral angles (IUPAC sign; Blondel & Karplus 1996, eq. 3) of (n, 4) atom indices, deg."""
    f, g = x[atoms[:, 0]] - x[atoms[:, 1]], x[atoms[:, 2]] - x[atoms[:, 1]]
    if atoms.shape[1] == 3:
        return np.degrees(np.arccos(np.clip(np.sum(f*g, axis=1)/np.linalg.norm(f, axis=1)/np.linalg.norm(g, axis=1), -1, 1)))
    a, b = np.cross(f, -g), np.cross(x[atoms[:, 3]] - x[atoms[:, 2]], -g)
    return np.degrees(np.arctan2(np.sum(np.cross(b, a)*-g, axis=1)/np.linalg.norm(g, axis=1), np.sum(a*b, axis=1)))

def analyse(counts, frames, phi, psi, energies):
    """A run's sample: from angles (frames x instances, by type as in counts {type: n}), phi and psi (frames x residues) and energies
    (frames x [bond, angle, torsion, U]), quantities [label, unit, mean, block standard error] and histograms (counts)."""
    def estimate(label, units, series, root=False):   # root: of a mean square, its root and the error propagated
        mean, error = blockMean(series)
        return [label, units] + ([np.sqrt(mean), error/(2*np.sqrt(mean)) if mean > 0 else 0.0] if root else [mean, error])
    quantities, histograms = [], {"phi": np.histogram(phi, RAMA)[0], "psi": np.histogram(psi, RAMA)[0]}
    for (name, n), start in zip(counts.items(), np.cumsum([0] + list(counts.values()))):
        values, histograms[name] = frames[:, start:start + n], np.histogram(frames[:, start:start + n], EDGES)[0]
        quantities += [estimate(f"angle {name} ({n}): mean", "deg", values.mean(axis=1)),
                       estimate(f"angle {name}: rms fluctuation", "deg", np.mean((values - values.mean(axis=0))**2, axis=1), True)]
    quantities += [estimate("phi/psi: fraction alpha-helical", "", np.mean(helical(phi, psi), axis=1))]
    quantities += [estimate(name, "kJ/mol", energies[:, k]) for k, name in enumerate(list(TERMS) + ["U (whole box)"])]
    quantities.append(estimate("U less the three bonded terms", "kJ/mol", energies[:, 3] - energies[:, :3].sum(axis=1)))
    return {"quantities": quantities, "histograms": {name: counts.tolist() for name, counts in histograms.items()}}

def measure(job, env):
    """A run from the minimum (bodies keep its shape): per frame the solute's geometry and original System's terms; the frozen terms."""
    settings, model, built = QUICK if env.quick else FULL, job["model"], build(job["system"], "plain")
    system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(built.system))
    for force in system.getForces(): force.setForceGroup(TERMS.get(type(force).__name__, 0))
    analysis = openmm.Context(system, openmm.VerletIntegrator(0.001), env.platform, env.properties)
    analysis.setState(setups.start(STARTS[job["system"]][0], built, env.platform, env.properties, STARTS[job["system"]][1]))
    openmm.LocalEnergyMinimizer.minimize(analysis, 10.0, settings["iterations"])
    bodies = [] if model == "flexible" else openmmrigid.rigidHydrogenGroups(built.topology, system, planarGroups=model == "xh-planar")
    integrator = setups.makeIntegrator("rigid-langevin" if bodies else "stock-middle", 2.0, job["seed"], TEMPERATURE, bodies=bodies or None)
    context = openmm.Context(openmmrigid.removeIntraBodyInteractions(system, bodies) if bodies else system, integrator, env.platform, env.properties)
    context.setState(analysis.getState(getPositions=True))
    context.setVelocitiesToTemperature(TEMPERATURE, job["seed"] + 1)
    energy = lambda c, group: c.getState(getEnergy=True, groups={group} if group else -1).getPotentialEnergy().value_in_unit(KJ)
    count = lambda c, g: sum(f.getNumBonds() if g == 1 else f.getNumAngles() for f in c.getSystem().getForces() if TERMS.get(type(f).__name__) == g)
    frozen = [[name, count(analysis, g) - count(context, g), energy(analysis, g) - energy(context, g)] for name, g in list(TERMS.items())[:2]]
    types, (phi, psi), frames = angleTypes(built.topology), backboneDihedrals(built.topology), []
    integrator.step(round(settings["equilibrate_ps"]*500))
    for _ in range(round(settings["production_ps"]*1000/settings["every_fs"])):
        integrator.step(round(settings["every_fs"]/2))
        now = context.getState(getPositions=True)
        analysis.setState(now)
        x = now.getPositions(asNumpy=True)._value
        frames.append((geometry(x, np.concatenate(list(types.values()))), geometry(x, phi), geometry(x, psi), [energy(analysis, g) for g in (1, 2, 3, None)]))
    angles, phis, psis, energies = (np.array(column) for column in zip(*frames))
    return dict(analyse({n: len(t) for n, t in types.items()}, angles, phis, psis, energies), frozen=frozen if bodies else [], bodies=len(bodies))

def summarize(results, env):
    """Per model: the quantities over its runs (overSeeds), the histograms summed, the frozen terms of one run."""
    settings, models = QUICK if env.quick else FULL, {}
    for runs, model in ((result["samples"], result["job"]["model"]) for result in results):
        models[model] = dict(runs[0], histograms={n: np.sum([r["histograms"][n] for r in runs], axis=0).tolist() for n in runs[0]["histograms"]},
                             quantities=[q[:2] + list(overSeeds([r["quantities"][k][2:] for r in runs])) for k, q in enumerate(runs[0]["quantities"])])
    return dict(system=results[0]["job"]["system"], temperature=TEMPERATURE, runs=len(results[0]["samples"]),
                frames=round(settings["production_ps"]*1000/settings["every_fs"]), frame_fs=settings["every_fs"], models=models)

def report(summary, page):
    models, kT = summary["models"], BOLTZMANN*summary["temperature"]
    value, others = {(m, q[0]): q[2:] for m in models for q in models[m]["quantities"]}, [m for m in models if m != "flexible"]
    shift = lambda m, f: (value[m, f][0] - value["flexible", f][0], np.hypot(value[m, f][1], value["flexible", f][1]))
    cell = lambda v, e: "{0:.{2}f} ± {1:.{2}f}".format(v, e, 4 if abs(v) < 1 else 2 if abs(v) < 1000 else 1)
    sigma = lambda d, e: (lambda s: f"**{s:+.1f}**" if abs(s) > 3 else f"{s:+.1f}")(d/e if e else 0.0 if d == 0 else np.inf)   # bold beyond 3
    page.text(f"{summary['runs']} run(s) per model, {summary['frames']} frames each, every {summary['frame_fs']:g} fs; mean ± standard error (block "
              "averages); rms fluctuation: of each angle about its own mean; last columns: the difference from flexible in combined errors.")
    page.table(["quantity", "unit"] + list(models) + [f"{m} - flexible (sigma)" for m in others],
               [q[:2] + [cell(*value[m, q[0]]) for m in models] + [sigma(*shift(m, q[0])) for m in others] for q in models["flexible"]["quantities"]])
    page.section("The bonded energy the bodies freeze", "A harmonic term inside one body keeps its energy in the minimized structure, E0, where "
                 f"the flexible model gives it about kT/2 more (equipartition, kT = {kT:.3f} kJ/mol): n frozen terms shift the mean by about -n kT/2.")
    page.table(["run", "force", "frozen terms n", "E0 (kJ/mol)", "-n kT/2 (kJ/mol)", "measured shift (kJ/mol)"],
               [[m, f, n, f"{round(e0, 1) + 0:.1f}", f"{-n*kT/2:.1f}", "{:.1f} ± {:.1f}".format(*shift(m, f))] for m in others for f, n, e0 in models[m]["frozen"]])
    names = list(models["flexible"]["histograms"])
    figure, axes = pyplot().subplots(-(-len(names)//4), 4, figsize=(13, 3.2*-(-len(names)//4)), squeeze=False)
    for axis, name in zip(axes.ravel(), names):
        edges, top = RAMA if name in ("phi", "psi") else EDGES, None
        for m, colour in zip(models, ["black", "tab:blue", "tab:orange"]):
            density = np.array(models[m]["histograms"][name])/np.sum(models[m]["histograms"][name])/np.diff(edges)
            axis.stairs(density, edges, color=colour, label=m)
            top = top or 1.3*density.max()   # the flexible model's: a frozen angle's spike is cut off
        axis.set(title=name, xlabel="deg", ylim=(0, top), xlim=(edges[0], edges[-1]) if name in ("phi", "psi") else (95, 130))
    axes[0, 0].legend(fontsize=7)
    page.figure(figure, "distributions", "Bond angles by type, phi and psi (all residues and frames); a frozen angle's spike is cut off")

STUDY = Study(
    "xh_groups_model", "Rigid X-H groups: the model change, measured", report=report,
    claim="Rigid X-H groups leave villin's heavy-atom angles, backbone dihedrals and nonbonded energy within about 3 standard errors of the flexible "
          "model and take about kT/2 per frozen H-X-H angle from the angle energy; planar groups also stiffen the angles around each peptide group.",
    method="""Villin (`setups.villin()`: amber14, TIP3P, PME 0.9 nm, HBonds), minimized; each run starts there at 310 K (1/ps, 2 fs, CPU): flexible,
stock `LangevinMiddleIntegrator`; xh-rigid, `RigidBodyLangevinIntegrator` with every X-H group and water a body (`openmmrigid.rigidHydrogenGroups`,
the minimum's shape; the System after `removeIntraBodyInteractions`); xh-planar, with `planarGroups=True` (rings, amides, peptide groups). After
3 ps, frames every 50 fs for 18 ps: the solute's bond angles by type, phi and psi, and the terms of the ORIGINAL System (one Hamiltonian).""",
    caveats="""One 18 ps trajectory per model: about 40 comparisons a column, so one beyond 3 sigma can be chance; slower quantities (rotamers,
helix fraying) are out of reach. The transcribed run: 1.0 nm padding, neutralized, 8 ps of the flexible model shared, then 1 ps per run.""",
    grid={"system": ["villin"], "model": ["flexible", "xh-rigid", "xh-planar"], "seed": [0]},
    quick={"system": ["dipeptide"], "model": ["flexible", "xh-rigid", "xh-planar"], "seed": [0]}, measure=measure, summarize=summarize)
