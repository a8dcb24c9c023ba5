#ifndef OPENMMRIGID_NUMERICS_SYMMETRICEIGEN_H_
#define OPENMMRIGID_NUMERICS_SYMMETRICEIGEN_H_

/*
 * Eigen-decomposition of small real symmetric matrices by the cyclic Jacobi method (Golub and
 * Van Loan, Matrix Computations, 4th ed., Section 8.5), and what the rigid-body code builds on it:
 * principal axes of a mass distribution and the best-fit rotation between two point sets
 * (B. K. P. Horn, J. Opt. Soc. Am. A 4, 629 (1987), Section 4).
 *
 * Accuracy: eigenvalues to a few ulps of the largest one; eigenvectors orthonormal to a few ulps.
 * Jacobi rotations are used because they are accurate for the nearly degenerate spectra of
 * symmetric molecules, where the closed-form cubic loses precision.
 */

#include "numerics/Matrix3.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

namespace OpenMMRigid {

/**
 * Eigenvalues (ascending) and eigenvectors (the columns of vectors) of the symmetric n x n matrix a,
 * stored row-major in a.size() == n*n entries. a is overwritten.
 */
inline void symmetricEigen(std::vector<double>& a, int n, std::vector<double>& values, std::vector<double>& vectors) {
    vectors.assign(n*n, 0.0);
    for (int i = 0; i < n; i++)
        vectors[i*n + i] = 1.0;
    auto at = [&](int i, int j) -> double& { return a[i*n + j]; };
    for (int sweep = 0; sweep < 64; sweep++) {
        double offDiagonal = 0.0, diagonal = 0.0;
        for (int i = 0; i < n; i++) {
            diagonal += at(i, i)*at(i, i);
            for (int j = i + 1; j < n; j++)
                offDiagonal += at(i, j)*at(i, j);
        }
        if (offDiagonal <= 1e-34*diagonal || offDiagonal == 0.0)
            break;
        for (int p = 0; p < n; p++)
            for (int q = p + 1; q < n; q++) {
                if (at(p, q) == 0.0)
                    continue;
                // The rotation that zeroes a_pq (Golub and Van Loan, Algorithm 8.5.1).
                double theta = (at(q, q) - at(p, p))/(2.0*at(p, q));
                double t = (theta >= 0.0 ? 1.0 : -1.0)/(std::fabs(theta) + std::sqrt(1.0 + theta*theta));
                double c = 1.0/std::sqrt(1.0 + t*t), s = t*c;
                for (int k = 0; k < n; k++) {
                    double akp = at(k, p), akq = at(k, q);
                    at(k, p) = c*akp - s*akq;
                    at(k, q) = s*akp + c*akq;
                }
                for (int k = 0; k < n; k++) {
                    double apk = at(p, k), aqk = at(q, k);
                    at(p, k) = c*apk - s*aqk;
                    at(q, k) = s*apk + c*aqk;
                }
                for (int k = 0; k < n; k++) {
                    double vkp = vectors[k*n + p], vkq = vectors[k*n + q];
                    vectors[k*n + p] = c*vkp - s*vkq;
                    vectors[k*n + q] = s*vkp + c*vkq;
                }
            }
    }
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int i, int j) { return at(i, i) < at(j, j); });
    std::vector<double> sortedVectors(n*n);
    values.resize(n);
    for (int j = 0; j < n; j++) {
        values[j] = at(order[j], order[j]);
        for (int k = 0; k < n; k++)
            sortedVectors[k*n + j] = vectors[k*n + order[j]];
    }
    vectors.swap(sortedVectors);
}

/**
 * The principal axes of point masses: the eigenvalues of the inertia tensor
 * I = sum m (|x|^2 - x x^T) about the given origin, ascending, and a proper rotation E whose columns
 * are the corresponding axes (det E = +1), so that body coordinates are E^T x.
 */
inline void principalAxes(const std::vector<Vector3>& x, const std::vector<double>& masses, Vector3& moments, Matrix3& axes) {
    std::vector<double> tensor(9, 0.0);
    for (size_t i = 0; i < x.size(); i++) {
        double r2 = dot(x[i], x[i]);
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                tensor[3*a + b] += masses[i]*((a == b ? r2 : 0.0) - x[i][a]*x[i][b]);
    }
    std::vector<double> values, vectors;
    symmetricEigen(tensor, 3, values, vectors);
    for (int a = 0; a < 3; a++) {
        moments[a] = std::max(values[a], 0.0);
        for (int b = 0; b < 3; b++)
            axes[a][b] = vectors[3*a + b];
    }
    if (determinant(axes) < 0.0)
        for (int a = 0; a < 3; a++)
            axes[a][2] = -axes[a][2];
}

/**
 * The rotation matrix (body to lab) that best maps the body coordinates b onto the lab coordinates x
 * in the weighted least-squares sense, minimizing sum_i w_i |R b_i - x_i|^2 (Horn 1987: the
 * eigenvector of the largest eigenvalue of the symmetric 4 x 4 matrix N built from
 * S = sum_i w_i b_i x_i^T is the unit quaternion of R). Both sets must be centred on the same
 * weighted centre.
 *
 * @param residual  on exit, sum_i w_i |R b_i - x_i|^2
 */
inline Matrix3 bestFitRotation(const std::vector<Vector3>& b, const std::vector<Vector3>& x,
                               const std::vector<double>& weights, double& residual) {
    double s[3][3] = {{0.0}};
    double norms = 0.0;
    for (size_t i = 0; i < b.size(); i++) {
        for (int p = 0; p < 3; p++)
            for (int q = 0; q < 3; q++)
                s[p][q] += weights[i]*b[i][p]*x[i][q];
        norms += weights[i]*(dot(b[i], b[i]) + dot(x[i], x[i]));
    }
    std::vector<double> n = {
        s[0][0] + s[1][1] + s[2][2], s[1][2] - s[2][1], s[2][0] - s[0][2], s[0][1] - s[1][0],
        s[1][2] - s[2][1], s[0][0] - s[1][1] - s[2][2], s[0][1] + s[1][0], s[2][0] + s[0][2],
        s[2][0] - s[0][2], s[0][1] + s[1][0], -s[0][0] + s[1][1] - s[2][2], s[1][2] + s[2][1],
        s[0][1] - s[1][0], s[2][0] + s[0][2], s[1][2] + s[2][1], -s[0][0] - s[1][1] + s[2][2]};
    std::vector<double> values, vectors;
    symmetricEigen(n, 4, values, vectors);
    double q0 = vectors[3], q1 = vectors[7], q2 = vectors[11], q3 = vectors[15];
    double size = std::sqrt(q0*q0 + q1*q1 + q2*q2 + q3*q3);
    q0 /= size; q1 /= size; q2 /= size; q3 /= size;
    residual = std::max(0.0, norms - 2.0*values[3]);
    return {{{q0*q0 + q1*q1 - q2*q2 - q3*q3, 2.0*(q1*q2 - q0*q3), 2.0*(q1*q3 + q0*q2)},
             {2.0*(q1*q2 + q0*q3), q0*q0 - q1*q1 + q2*q2 - q3*q3, 2.0*(q2*q3 - q0*q1)},
             {2.0*(q1*q3 - q0*q2), 2.0*(q2*q3 + q0*q1), q0*q0 - q1*q1 - q2*q2 + q3*q3}}};
}

} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_SYMMETRICEIGEN_H_
