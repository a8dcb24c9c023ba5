/*
 * The numerics core, part 6: the arithmetic of one step of the stochastic velocity rescaling
 * thermostat of G. Bussi, D. Donadio and M. Parrinello, J. Chem. Phys. 126, 014101 (2007), given
 * its random deviates. The kinetic energy K of N_f degrees of freedom follows (their eq. (7))
 *
 *     dK = (Kbar - K) dt/tau + 2 sqrt(K Kbar/(N_f tau)) dW,    Kbar = N_f kT/2,
 *
 * and over a time t, with c = exp(-t/tau), its exact solution is (their eq. (A7))
 *
 *     K' = c K + (1 - c) Kbar (R_1^2 + S)/N_f + 2 R_1 sqrt(c (1 - c) K Kbar/N_f),
 *
 * R_1 a standard normal deviate and S a chi-squared deviate with N_f - 1 degrees of freedom. The
 * velocities are scaled by alpha = sqrt(K'/K), whose sign is that of
 * R_1 + sqrt(c N_f K/((1 - c) Kbar)) (their eq. (A8)): negative only in the rare case that the
 * scaling passes through zero.
 *
 * The deviates do not depend on K: the host draws them (numerics/StochasticRescaling.h, which also
 * states how) and a device that holds K applies this function without the host reading K. See
 * numerics/RigidCore.h for the rules every core file follows.
 *
 * Accuracy: exact to the rounding of the dozen operations below.
 */
#ifndef OPENMMRIGID_CORE_THERMOSTAT_H_
#define OPENMMRIGID_CORE_THERMOSTAT_H_

/**
 * The factor alpha by which every velocity is scaled in one step of the thermostat, and (in
 * *newKinetic) the new kinetic energy alpha^2 K.
 *
 * kinetic is K (for K <= 0 nothing can be scaled: alpha is 1); targetKinetic is Kbar = N_f kT/2
 * (<= 0 damps: K' = c K, alpha = sqrt(c)); dof is N_f (<= 0: alpha is 1); c = exp(-t/tau) (>= 1:
 * no coupling, alpha is 1); r1 is R_1 and rest is S, the deviates of eq. (A7).
 */
RIGID_FUNCTION double rigidStochasticRescaling(double kinetic, double targetKinetic, int dof, double c, double r1, double rest,
                                               double* newKinetic) {
    double alpha;
    *newKinetic = kinetic;
    if (!(kinetic > 0.0) || dof <= 0 || c >= 1.0)
        return 1.0;
    if (targetKinetic <= 0.0) {
        /* eq. (A7) with Kbar = 0 */
        *newKinetic = c*kinetic;
        return sqrt(c);
    }
    /* Bussi, Donadio and Parrinello (2007), eq. (A7) */
    *newKinetic = c*kinetic + (1.0 - c)*targetKinetic*(r1*r1 + rest)/dof + 2.0*r1*sqrt(c*(1.0 - c)*kinetic*targetKinetic/dof);
    alpha = sqrt(*newKinetic/kinetic);
    /* eq. (A8): the sign of alpha */
    if (r1 + sqrt(c*dof*kinetic/((1.0 - c)*targetKinetic)) < 0.0)
        alpha = -alpha;
    return alpha;
}

#endif /* OPENMMRIGID_CORE_THERMOSTAT_H_ */
