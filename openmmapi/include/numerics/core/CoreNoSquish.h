/*
 * The numerics core, part 4: the NO_SQUISH free rotation of T. F. Miller III, M. Eleftheriou,
 * P. Pattnaik, A. Ndirango, D. Newns and G. J. Martyna, J. Chem. Phys. 116, 8649 (2002), Section II.B:
 * the rotational kinetic energy sum_k L_k^2 / (2 I_k) is split into its three terms, each of which is
 * a uniform rotation about one body axis, composed symmetrically as
 *   R_3(dt/2) R_2(dt/2) R_1(dt) R_2(dt/2) R_3(dt/2)   (their eq. (2.17) written with the body axes).
 * The composition is symplectic and time-reversible and second order in dt. Miller et al. write it
 * for a quaternion and its conjugate momentum; here the same rotations act on the attitude A (lab to
 * body) and the body-frame angular momentum: under the term L_k^2/(2 I_k) alone the body turns about
 * its axis k at the rate L_k/I_k, so both A and L_body are multiplied by the rotation U(-phi e_k),
 * phi = (L_k/I_k) dt, and L_lab = A^T L_body stays fixed.
 *
 * Exact up to rounding for the splitting it implements; its error against the true free motion is
 * O(dt^3) per step (benchmarks/studies/rotation_accuracy.py measures it against FreeRotor).
 * See numerics/RigidCore.h for the rules every core file follows.
 */
#ifndef OPENMMRIGID_CORE_NOSQUISH_H_
#define OPENMMRIGID_CORE_NOSQUISH_H_

/** Apply U(-angle e_axis) to A (on the left) and to the body-frame vector l. */
RIGID_FUNCTION void rigidRotateAboutBodyAxis(int axis, double angle, double attitude[3][3], double* l) {
    const int i = (axis + 1)%3, j = (axis + 2)%3;
    const double c = cos(angle), s = sin(angle);
    double li, lj;
    int column;
    /* U(-angle e_axis) maps (v_i, v_j) to (c v_i + s v_j, -s v_i + c v_j). */
    for (column = 0; column < 3; column++) {
        const double ai = attitude[i][column], aj = attitude[j][column];
        attitude[i][column] = c*ai + s*aj;
        attitude[j][column] = -s*ai + c*aj;
    }
    li = l[i];
    lj = l[j];
    l[i] = c*li + s*lj;
    l[j] = -s*li + c*lj;
}

/**
 * Advance a free rigid rotor by dt with the NO_SQUISH splitting.
 *
 * @param moments          the principal moments (a zero moment marks the axis of a linear body, which
 *                         carries no angular momentum and is skipped)
 * @param dt               the time step
 * @param attitude         A (lab to body), advanced in place
 * @param angularMomentum  the angular momentum in the body frame, advanced in place
 */
RIGID_FUNCTION void rigidNoSquishRotate(const double* moments, double dt, double attitude[3][3], double* angularMomentum) {
    int step;
    for (step = 0; step < 5; step++) {
        /* the axes 2, 1, 0, 1, 2 with the fractions 1/2, 1/2, 1, 1/2, 1/2 of dt */
        const int k = (step < 2 ? 2 - step : step - 2);
        const double fraction = (step == 2 ? 1.0 : 0.5);
        if (moments[k] > 0.0)
            rigidRotateAboutBodyAxis(k, angularMomentum[k]/moments[k]*fraction*dt, attitude, angularMomentum);
    }
}

#endif /* OPENMMRIGID_CORE_NOSQUISH_H_ */
