#ifndef OPENMMRIGID_NUMERICS_MATRIX3_H_
#define OPENMMRIGID_NUMERICS_MATRIX3_H_

/*
 * Small fixed-size vector and matrix helpers on plain doubles (layer 1 of the plugin: no OpenMM
 * types). Matrices are row-major, M[i][j] is row i, column j. All functions are exact up to the
 * rounding of the few products and sums they perform.
 */

#include "numerics/RigidCore.h"
#include <array>
#include <cmath>

namespace OpenMMRigid {

using Vector3 = std::array<double, 3>;
using Matrix3 = std::array<std::array<double, 3>, 3>;

inline Matrix3 identityMatrix() {
    return {{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
}

inline double dot(const Vector3& a, const Vector3& b) {
    return a[0]*b[0] + a[1]*b[1] + a[2]*b[2];
}

inline double norm(const Vector3& a) {
    return rigidNorm(a.data());
}

inline Vector3 cross(const Vector3& a, const Vector3& b) {
    return {a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]};
}

inline Vector3 scaled(const Vector3& a, double s) {
    return {a[0]*s, a[1]*s, a[2]*s};
}

inline Matrix3 multiply(const Matrix3& a, const Matrix3& b) {
    Matrix3 c;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[i][j] = a[i][0]*b[0][j] + a[i][1]*b[1][j] + a[i][2]*b[2][j];
    return c;
}

/** The product a^T b. */
inline Matrix3 multiplyTransposed(const Matrix3& a, const Matrix3& b) {
    Matrix3 c;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[i][j] = a[0][i]*b[0][j] + a[1][i]*b[1][j] + a[2][i]*b[2][j];
    return c;
}

inline Vector3 multiply(const Matrix3& a, const Vector3& v) {
    return {a[0][0]*v[0] + a[0][1]*v[1] + a[0][2]*v[2],
            a[1][0]*v[0] + a[1][1]*v[1] + a[1][2]*v[2],
            a[2][0]*v[0] + a[2][1]*v[1] + a[2][2]*v[2]};
}

/** The product a^T v. */
inline Vector3 multiplyTransposed(const Matrix3& a, const Vector3& v) {
    return {a[0][0]*v[0] + a[1][0]*v[1] + a[2][0]*v[2],
            a[0][1]*v[0] + a[1][1]*v[1] + a[2][1]*v[2],
            a[0][2]*v[0] + a[1][2]*v[1] + a[2][2]*v[2]};
}

inline Matrix3 transpose(const Matrix3& a) {
    return {{{a[0][0], a[1][0], a[2][0]}, {a[0][1], a[1][1], a[2][1]}, {a[0][2], a[1][2], a[2][2]}}};
}

inline double determinant(const Matrix3& a) {
    return a[0][0]*(a[1][1]*a[2][2] - a[1][2]*a[2][1])
         - a[0][1]*(a[1][0]*a[2][2] - a[1][2]*a[2][0])
         + a[0][2]*(a[1][0]*a[2][1] - a[1][1]*a[2][0]);
}

/** The largest entry of |a^T a - 1|: how far a is from orthonormal. */
inline double orthonormalityError(const Matrix3& a) {
    // a^T a is symmetric to the last bit (its (i, j) and (j, i) entries are the same products), so
    // the upper triangle holds every value; a NaN entry is passed over, as std::fmax does.
    double worst = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++) {
            double g = a[0][i]*a[0][j] + a[1][i]*a[1][j] + a[2][i]*a[2][j];
            double error = std::fabs(g - (i == j ? 1.0 : 0.0));
            if (error > worst)
                worst = error;
        }
    return worst;
}

} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_MATRIX3_H_
