"""The configuration-space KL estimate of sampling_error on a solvated protein: each integrator against its own model's
Boltzmann distribution, at the steps protein_step_cap found accurate."""

from harness import Study
from studies import sampling_error

STUDY = Study(
    "protein_sampling_error", "Configuration-space sampling error on a solvated protein",
    claim="On villin the configuration-space KL estimate of RigidBodyLangevinIntegrator with rigid X-H and planar groups and the "
          "bonded forces every 1 fs is within errors of 0 at 10 fs (0.2 ± 1.8 kT), as stock LangevinMiddleIntegrator's with HMR at "
          "4 fs (-0.1 ± 2.9 kT); with the bonded forces every 2 fs it reads 3.1 ± 1.4 kT at 10 fs, and at 12 fs 8 to 9 kT (2.5 "
          "errors) with either.",
    method="""sampling_error's protocol (per frame: velocities drawn, 2 ps summing the shadow work w_π, drawn again, 2 ps w_ω;
KL ≈ (⟨w_π⟩ − ⟨w_ω⟩)/2 ± the standard error of the paired halves, on-step velocities at both ends) on villin HP35 in TIP3P
(protein_mts's, 10,613 particles; amber14, PME 0.9 nm, HBonds), each integrator against its own model: villin-hmr, the
flexible model with HMR 3 amu, run by stock-middle (LangevinMiddleIntegrator's step as a CustomIntegrator summing its
shadow work) at 4 fs, as users run it; villin-planar, every X-H group, planar group (peptide groups, rings, amides) and
water a rigid body (`openmmrigid.rigidHydrogenGroups(..., planarGroups=True)`) with moments raised to 0.16 amu nm², run by
rigid-mts and rigid-mts-2fs (RigidBodyLangevinIntegrator with the protein's bonded forces in 1 fs or 2 fs substeps) at 10 and
12 fs. Frames: each
model's own integrator at 1 fs and 5/ps, 5 ps from protein_mts's equilibrated start with fresh velocities, then one every
2 ps. A KL is extensive: a whole system's, in kT. ns/day: the integrators as users run them, side by side.""",
    caveats="""Each integrator is judged on its own model, not the models against each other (xh_groups_model measures the
model change). The rigid bodies keep the shapes they have in protein_mts's equilibrated start, a thermal snapshot of the
flexible model. One protein, 12 frames 2 ps apart from one run; the estimate is near-equilibrium (Sivak, Chodera and Crooks
2013) and its bias is not measured.""",
    report=sampling_error.report,
    grid=[{"system": ["villin-hmr"], "integrator": ["stock-middle"], "step": [4], "seed": list(range(12))},
          {"system": ["villin-planar"], "integrator": ["rigid-mts", "rigid-mts-2fs"], "step": [10, 12], "seed": list(range(12))}],
    quick=[{"system": ["dipeptide-hmr"], "integrator": ["stock-middle"], "step": [2, 4], "seed": [0, 1]},
           {"system": ["dipeptide-planar"], "integrator": ["rigid-mts"], "step": [2, 12], "seed": [0, 1]}],
    measure=sampling_error.measure, summarize=sampling_error.summarize)
