"""What caps the outer step of rigid X-H groups with multiple time steps on a solvated protein, one thing changed at a time
as step_cap did for water, and how far rigid planar groups take it, on villin and on DHFR."""

from harness import Study
from studies import protein_mts

PROBES = ["xh-mts", "xh-mts-1fs", "xh-mts-0.32", "xh-mts-f5"]   # protein_mts.CONFIGURATIONS and OVERRIDES
TITLES = {"villin": ("Villin: the outer step, the substep, each change alone at 12 fs, and planar groups", "six runs a row (three at 12 fs "
                     "with one change)"),
          "dhfr": ("DHFR (JAC, 23,558 particles): the recipe on a larger protein", "four runs a row")}


def report(summary, page):
    for system in dict.fromkeys(row["system"] for row in summary["rows"]):
        title, runs = TITLES[system] if system in TITLES else (system, "")
        protein_mts.section(page, title, f"Biases against the same model at 2 fs ({runs}; stock: flexible; rigid X-H groups: moments "
                            "raised to 0.16 amu nm^2, friction 1/ps), bold beyond two standard errors; speed of every row timed side by "
                            "side in one process.", rows := [row for row in summary["rows"] if row["system"] == system])
        protein_mts.biasFigure(page, system, rows)


STUDY = Study(
    "protein_step_cap", "What caps the outer step on a solvated protein, and how far planar groups take it",
    claim="Rigid X-H and planar groups (peptide groups, rings, amides) with the bonded forces every 2 fs keep U and the solute's "
          "bonded energy within two standard errors of their model to 10 fs at 2.2 (villin) and 1.9 (DHFR) times the ns/day of stock "
          "HMR at 4 fs: they freeze the C=O and ring stretches whose resonance with the outer kicks caps rigid X-H groups alone at "
          "8 fs (1.65 times, bonded every 1 fs: every 2 fs the inner Verlet's error on those stretches biases the bonded energy by "
          "+50 kJ/mol); stock MTSLangevinIntegrator is capped by the water (U +1016 kJ/mol at 6 fs).",
    method="""Villin in TIP3P as in protein_mts, with six runs a row where protein_mts has three: stock LangevinMiddle at 2 fs and with
HMR at 4 fs, rigid X-H groups (moments raised to 0.16 amu nm^2) at 2 fs, and with the bonded forces in 2 fs or 1 fs substeps at 4, 8
and 10 fs (does the bias depend on the outer step or on the substep?); then three runs each at 12 fs with one change: the
bonded forces in 1 fs substeps (if the inner integration capped the step, the bias would go), moments raised to 0.32 amu nm^2 (the
X-H groups' rotation, driven by the nonbonded forces at the outer step, twice as slow: if it capped the step, the bias would go), or
the friction raised to 5/ps (a thermostat strong enough to drain the energy a resonance of the outer kicks with the heavy-atom
bonds' vibrations pumps in; the configurational distribution is the same). Then the remedy the resonance points to: rigid planar
groups too (`rigidHydrogenGroups(..., planarGroups=True)`: peptide groups, rings, amides, which freeze the C=O and ring
stretches), against their own model at 2 fs, with 1 fs or 2 fs substeps from 8 to 14 fs; and the same on DHFR (the JAC benchmark,
`setups.dhfr()`: the benchmark's Amber prmtop, TIP3P, 23,558 particles, PME 0.9 nm; four runs a row), where each run also records the
solute's temperature, its share of alpha-helical phi/psi and the rms fluctuation of phi and psi (protein_mts.measure). Runs as
in protein_mts: 1 ps discarded, 4 ps sampled. Why the inner Verlet biases the bonded energy where the single-step reference does
not: velocity Verlet samples a harmonic mode of frequency w with <x^2> too large by 1/(1 - (w h/2)^2), about 10 % for a C=O
stretch at h = 2 fs, 2.5 % at 1 fs, where BAOAB with one step (the reference) samples it exactly.""",
    caveats="""Two proteins, U resolved to about 150 (villin) or 200 to 300 kJ/mol (DHFR) and the bonded energy to about 10 to 25: a
cap is named only where one change removes a bias the others leave. Friction 5/ps slows the dynamics five times: a remedy for
sampling, not for dynamics. The solute's temperature is read from the held velocities (half a step behind for the rigid
integrator, on-step for stock), whose reading of stiff modes differs with the step: it is not ruled on, like T. Helix share and
dihedral fluctuation are within-basin observables of 4 ps runs: no transitions are sampled. The planar groups change the model
(xh_groups_model); CPU only: the substeps' cost is the CPU platform's bonded kernels (about 1 ms per substep on DHFR), which a GPU
changes.""",
    grid=[{"system": ["villin"], "configuration": ["xh"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["stock"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["stock-hmr"], "step": [4], "seed": range(6)},
          {"system": ["villin"], "configuration": ["stock-mts"], "step": [6, 8], "seed": range(6)},
          {"system": ["villin"], "configuration": ["xh-mts", "xh-mts-1fs"], "step": [4, 8, 10], "seed": range(6)},
          {"system": ["villin"], "configuration": PROBES, "step": [12], "seed": [0, 1, 2]},
          {"system": ["villin"], "configuration": ["planar"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["planar-mts"], "step": [8, 10, 12, 14], "seed": range(6)},
          {"system": ["villin"], "configuration": ["planar-mts-2fs"], "step": [10, 12], "seed": range(6)},
          {"system": ["dhfr"], "configuration": ["stock", "planar"], "step": [2], "seed": range(4)},
          {"system": ["dhfr"], "configuration": ["stock-hmr"], "step": [4], "seed": range(4)},
          {"system": ["dhfr"], "configuration": ["planar-mts", "planar-mts-2fs"], "step": [10, 12], "seed": range(4)}],
    quick=[{"system": ["dipeptide"], "configuration": ["xh"], "step": [2], "seed": [0]},
           {"system": ["dipeptide"], "configuration": PROBES + ["planar-mts", "planar-mts-2fs"], "step": [6], "seed": [0]},
           {"system": ["dipeptide"], "configuration": ["planar"], "step": [2], "seed": [0]},
           {"system": ["dipeptide"], "configuration": ["stock"], "step": [2], "seed": [0]},
           {"system": ["dipeptide"], "configuration": ["stock-mts"], "step": [6], "seed": [0]}],
    measure=protein_mts.measure, summarize=protein_mts.summarize, report=report)
