"""What caps the outer step of rigid X-H groups with multiple time steps on a solvated protein: at 12 fs, where the
solute's bonded energy rises (protein_mts), one thing changed at a time, as step_cap did for water."""

from harness import Study
from studies import protein_mts

PROBES = ["xh-mts", "xh-mts-1fs", "xh-mts-0.32", "xh-mts-f5"]   # protein_mts.CONFIGURATIONS and OVERRIDES


def summarize(results, env):
    return {"rows": protein_mts.biasRows(results)[0]}


def report(summary, page):
    rows = summary["rows"]
    protein_mts.section(page, "Each change alone at 12 fs", "Biases against the same model at 2 fs (rigid X-H groups, moments "
                        "raised to 0.16 amu nm^2, friction 1/ps), bold beyond two standard errors.", rows)


STUDY = Study(
    "protein_step_cap", "What caps the outer step on a solvated protein",
    claim="PENDING",
    method="""Villin in TIP3P as in protein_mts, rigid X-H groups with moments raised to 0.16 amu nm^2 and the bonded forces in 2 fs
substeps, at 10 fs (accurate there) and 12 fs (the solute's bonded energy too high there), against 12 fs with one change each: the
bonded forces in 1 fs substeps (if the inner integration capped the step, the bias would go), moments raised to 0.32 amu nm^2 (the
X-H groups' rotation, driven by the nonbonded forces at the outer step, twice as slow: if it capped the step, the bias would go), or
the friction raised to 5/ps (a thermostat strong enough to drain the energy a resonance of the outer kicks with the heavy-atom
bonds' vibrations pumps in; the configurational distribution is the same). Runs and rows as in protein_mts: 3 seeds, 1 ps
discarded, 4 ps sampled, against the model at 2 fs.""",
    caveats="""One protein, three runs a row, U resolved to about 200 kJ/mol and the bonded energy to about 30: a cap is named only
where one change removes a bias the others leave. Friction 5/ps slows the dynamics five times: a remedy for sampling, not for
dynamics.""",
    grid=[{"system": ["villin"], "configuration": ["xh"], "step": [2], "seed": range(6)},
          {"system": ["villin"], "configuration": ["xh-mts"], "step": [8, 10], "seed": range(6)},
          {"system": ["villin"], "configuration": ["xh-mts"], "step": [12], "seed": [0, 1, 2]},
          {"system": ["villin"], "configuration": PROBES[1:], "step": [12], "seed": [0, 1, 2]}],
    quick=[{"system": ["dipeptide"], "configuration": ["xh"], "step": [2], "seed": [0]},
           {"system": ["dipeptide"], "configuration": PROBES, "step": [6], "seed": [0]}],
    measure=protein_mts.measure, summarize=summarize, report=report)
