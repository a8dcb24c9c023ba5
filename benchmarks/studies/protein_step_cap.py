"""What caps the outer step of rigid X-H groups with multiple time steps on a solvated protein: at 12 fs, where the
solute's bonded energy rises (protein_mts), one thing changed at a time, as step_cap did for water."""

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
                            "side in one process.", [row for row in summary["rows"] if row["system"] == system])


STUDY = Study(
    "protein_step_cap", "What caps the outer step on a solvated protein",
    claim="With six runs a row, rigid X-H groups with the bonded forces in 2 fs substeps carry a bonded-energy bias of about "
          "+50 kJ/mol at every outer step from 4 fs (the inner velocity Verlet's own error), which 1 fs substeps remove up to 8 fs "
          "(1.6 times stock HMR 4 fs, itself +328 kJ/mol in U at this resolution); from 10 fs a bias returns whatever the "
          "substep, at 12 fs it is not the X-H groups' rotation (a doubled moment does not help) and a friction of 5/ps drains "
          "it: the outer kicks pump the heavy-atom vibrations.",
    method="""Villin in TIP3P as in protein_mts, with six runs a row where protein_mts has three: stock LangevinMiddle at 2 fs and with
HMR at 4 fs, rigid X-H groups (moments raised to 0.16 amu nm^2) at 2 fs, and with the bonded forces in 2 fs or 1 fs substeps at 4, 8
and 10 fs (does the bias depend on the outer step or on the substep?); then three runs each at 12 fs with one change: the
bonded forces in 1 fs substeps (if the inner integration capped the step, the bias would go), moments raised to 0.32 amu nm^2 (the
X-H groups' rotation, driven by the nonbonded forces at the outer step, twice as slow: if it capped the step, the bias would go), or
the friction raised to 5/ps (a thermostat strong enough to drain the energy a resonance of the outer kicks with the heavy-atom
bonds' vibrations pumps in; the configurational distribution is the same). Runs as in protein_mts: 1 ps discarded, 4 ps
sampled. Why the inner Verlet biases the bonded energy where the single-step reference does not: velocity Verlet samples a
harmonic mode of frequency w with <x^2> too large by 1/(1 - (w h/2)^2), about 10 % for a C=O stretch at h = 2 fs, 2.5 % at 1 fs,
where BAOAB with one step (the reference) samples it exactly.""",
    caveats="""One protein, U resolved to about 150 kJ/mol and the bonded energy to about 10 (six runs) or 20 (three): a cap is named
only where one change removes a bias the others leave. Friction 5/ps slows the dynamics five times: a remedy for sampling, not for
dynamics, and at 12 fs with 2 fs substeps its +26 +- 13 does not exclude the inner Verlet's +50.""",
    grid=[{"system": ["villin"], "configuration": ["xh"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["stock"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["stock-hmr"], "step": [4], "seed": range(6)},
          {"system": ["villin"], "configuration": ["xh-mts", "xh-mts-1fs"], "step": [4, 8, 10], "seed": range(6)},
          {"system": ["villin"], "configuration": PROBES, "step": [12], "seed": [0, 1, 2]},
          {"system": ["villin"], "configuration": ["planar"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["planar-mts"], "step": [8, 10, 12, 14], "seed": range(6)},
          {"system": ["villin"], "configuration": ["planar-mts-2fs"], "step": [10, 12], "seed": range(6)},
          {"system": ["dhfr"], "configuration": ["stock", "planar"], "step": [2], "seed": range(4)},
          {"system": ["dhfr"], "configuration": ["stock-hmr"], "step": [4], "seed": range(4)},
          {"system": ["dhfr"], "configuration": ["planar-mts", "planar-mts-2fs"], "step": [10, 12], "seed": range(4)}],
    quick=[{"system": ["dipeptide"], "configuration": ["xh"], "step": [2], "seed": [0]},
           {"system": ["dipeptide"], "configuration": PROBES + ["planar-mts"], "step": [6], "seed": [0]},
           {"system": ["dipeptide"], "configuration": ["planar"], "step": [2], "seed": [0]}],
    measure=protein_mts.measure, summarize=protein_mts.summarize, report=report)
