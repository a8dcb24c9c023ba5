#ifndef OPENMMRIGID_PYTHON_FREEROTORADAPTOR_H_
#define OPENMMRIGID_PYTHON_FREEROTORADAPTOR_H_

/*
 * The bridge between the Python class openmmrigid.FreeRotor and OpenMMRigid::FreeRotor: everything
 * goes through flat arrays of doubles, so that Python passes numpy buffers and the loop over times
 * runs in C++. Not public API; Python users see openmmrigid.FreeRotor.
 */

#include "numerics/FreeRotor.h"

#include <cstddef>
#include <stdexcept>
#include <string>

namespace OpenMMRigid {

class FreeRotorAdaptor {
public:
    /**
     * Build the rotor. moments (3), omega (3, body frame) and attitude (9, the lab-to-body matrix
     * row by row) are in any consistent units; representation is a FreeRotor::Representation.
     */
    FreeRotorAdaptor(const double* moments, std::size_t momentsLength, const double* omega, std::size_t omegaLength,
                     const double* attitude, std::size_t attitudeLength, int representation) :
            rotor(toVector3(moments, momentsLength, "moments"), toVector3(omega, omegaLength, "omega"),
                  toMatrix3(attitude, attitudeLength, "attitude"), toRepresentation(representation)) {
    }
    /**
     * Evaluate the motion at each of the numTimes times: omegaOut receives 3 entries per time,
     * attitudeOut 9 (row by row).
     */
    void evolveInto(const double* times, std::size_t numTimes, double* omegaOut, std::size_t omegaLength,
                    double* attitudeOut, std::size_t attitudeLength) const {
        requireLength("omegaOut", omegaLength, 3*numTimes);
        requireLength("attitudeOut", attitudeLength, 9*numTimes);
        Vector3 omega;
        Matrix3 attitude;
        for (std::size_t k = 0; k < numTimes; k++) {
            rotor.evolve(times[k], omega, attitude);
            for (int i = 0; i < 3; i++) {
                omegaOut[3*k + i] = omega[i];
                for (int j = 0; j < 3; j++)
                    attitudeOut[9*k + 3*i + j] = attitude[i][j];
            }
        }
    }
    const char* getKind() const {
        return FreeRotor::kindName(rotor.getKind());
    }
    int getRepresentation() const {
        return rotor.getRepresentation();
    }
    double getEnergy() const {
        return rotor.getEnergy();
    }
    double getParameter() const {
        return rotor.getParameter();
    }
    void getAngularMomentum(double* out, std::size_t length) const {
        copyVector(rotor.getAngularMomentum(), out, length, "angularMomentum");
    }
    void getMoments(double* out, std::size_t length) const {
        copyVector(rotor.getMoments(), out, length, "moments");
    }
    void getOmega(double* out, std::size_t length) const {
        copyVector(rotor.getOmega(), out, length, "omega");
    }
    void getAttitude(double* out, std::size_t length) const {
        requireLength("attitude", length, 9);
        const Matrix3& attitude = rotor.getAttitude();
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                out[3*i + j] = attitude[i][j];
    }
private:
    static void requireLength(const char* name, std::size_t length, std::size_t expected) {
        if (length != expected)
            throw std::invalid_argument(std::string(name) + " must hold " + std::to_string(expected) +
                                        " numbers; got " + std::to_string(length));
    }
    static Vector3 toVector3(const double* values, std::size_t length, const char* name) {
        requireLength(name, length, 3);
        return {values[0], values[1], values[2]};
    }
    static Matrix3 toMatrix3(const double* values, std::size_t length, const char* name) {
        requireLength(name, length, 9);
        return {{{values[0], values[1], values[2]}, {values[3], values[4], values[5]}, {values[6], values[7], values[8]}}};
    }
    static FreeRotor::Representation toRepresentation(int representation) {
        if (representation != FreeRotor::Automatic && representation != FreeRotor::ThetaSeries &&
                representation != FreeRotor::EllipticIntegral)
            throw std::invalid_argument("unknown free-rotor representation " + std::to_string(representation));
        return static_cast<FreeRotor::Representation>(representation);
    }
    static void copyVector(const Vector3& vector, double* out, std::size_t length, const char* name) {
        requireLength(name, length, 3);
        for (int i = 0; i < 3; i++)
            out[i] = vector[i];
    }
    FreeRotor rotor;
};

} // namespace OpenMMRigid

#endif // OPENMMRIGID_PYTHON_FREEROTORADAPTOR_H_
