#ifndef OPENMMRIGID_NUMERICS_PHILOX_H_
#define OPENMMRIGID_NUMERICS_PHILOX_H_

/*
 * Counter-based random numbers for the host code: Philox4x32-10 (Salmon et al., Proc. SC11 (2011))
 * and its standard normal deviates, the core's rigidPhilox4x32() and RigidNormalStream
 * (numerics/core/CorePhilox.h, which states the method and its accuracy) behind std::array and a
 * small class, so that host and kernels draw the same numbers.
 */

#include "numerics/RigidCore.h"
#include <array>
#include <cstdint>

namespace OpenMMRigid {

/** Philox4x32-10: the 4-word output block for a 4-word counter and a 2-word key. */
inline std::array<uint32_t, 4> philox4x32(std::array<uint32_t, 4> counter, std::array<uint32_t, 2> key) {
    std::array<uint32_t, 4> block;
    rigidPhilox4x32(counter.data(), key.data(), block.data());
    return block;
}

/**
 * A stream of standard normal (and uniform) deviates for one (key, stream, step): block b of the stream is the
 * Philox output for the counter (stream, step low word, step high word, b). Streams with different
 * (stream, step) never share a counter, so their numbers are independent.
 */
class NormalStream {
public:
    NormalStream(uint64_t seed, uint32_t stream, uint64_t step) {
        rigidNormalStreamInitialize(&state, seed, stream, step);
    }
    /** The next standard normal deviate. */
    double next() {
        return rigidNormalStreamNext(&state);
    }
    /** The next uniform deviate in (0, 1), from 53 bits of two output words. */
    double uniform() {
        return rigidNormalStreamUniform(&state);
    }
private:
    RigidNormalStream state;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_NUMERICS_PHILOX_H_*/
