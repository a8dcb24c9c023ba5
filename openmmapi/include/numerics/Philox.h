#ifndef OPENMMRIGID_NUMERICS_PHILOX_H_
#define OPENMMRIGID_NUMERICS_PHILOX_H_

/*
 * Counter-based random numbers: the Philox4x32-10 generator of J. K. Salmon, M. A. Moraes,
 * R. O. Dror and D. E. Shaw, "Parallel random numbers: as easy as 1, 2, 3", Proc. SC11 (2011),
 * and standard normal deviates from it by the Box-Muller transform.
 *
 * A counter-based generator is a keyed bijection of a 128-bit counter: the numbers for a given
 * (key, counter) do not depend on what was drawn before, so each body of each step can draw its own
 * numbers on any thread and a trajectory depends only on the seed (the key) and the step and body
 * (the counter). Philox4x32-10 passes the BigCrush battery of TestU01 (Salmon et al., Table 2); the
 * tests check it against the known-answer vectors of the authors' Random123 library.
 *
 * Accuracy of the deviates: uniforms carry 53 random bits and lie in (0, 1) (never 0, so the
 * logarithm of Box-Muller is finite); the normal deviates are then exact to rounding, with tails cut
 * at |x| < sqrt(-2 ln 2^-54), about 8.7 (probability 4e-18).
 */

#include <array>
#include <cmath>
#include <cstdint>

namespace OpenMMRigid {

/** Philox4x32-10: the 4-word output block for a 4-word counter and a 2-word key. */
inline std::array<uint32_t, 4> philox4x32(std::array<uint32_t, 4> counter, std::array<uint32_t, 2> key) {
    // Salmon et al. (2011), Sec. 4.2: the multipliers and the Weyl key schedule of Philox4x32.
    const uint32_t multiplier0 = 0xD2511F53, multiplier1 = 0xCD9E8D57;
    const uint32_t weyl0 = 0x9E3779B9, weyl1 = 0xBB67AE85;
    for (int round = 0; round < 10; round++) {
        if (round > 0) {
            key[0] += weyl0;
            key[1] += weyl1;
        }
        uint64_t product0 = (uint64_t) multiplier0*counter[0];
        uint64_t product1 = (uint64_t) multiplier1*counter[2];
        uint32_t high0 = (uint32_t) (product0 >> 32), low0 = (uint32_t) product0;
        uint32_t high1 = (uint32_t) (product1 >> 32), low1 = (uint32_t) product1;
        counter = {high1 ^ counter[1] ^ key[0], low1, high0 ^ counter[3] ^ key[1], low0};
    }
    return counter;
}

/**
 * A stream of standard normal (and uniform) deviates for one (key, stream, step): block b of the stream is the
 * Philox output for the counter (stream, step low word, step high word, b). Streams with different
 * (stream, step) never share a counter, so their numbers are independent.
 */
class NormalStream {
public:
    NormalStream(uint64_t seed, uint32_t stream, uint64_t step) : key({(uint32_t) seed, (uint32_t) (seed >> 32)}),
            counter({stream, (uint32_t) step, (uint32_t) (step >> 32), 0}), used(4), spare(false), spareValue(0.0) {
    }
    /** The next standard normal deviate. */
    double next() {
        if (spare) {
            spare = false;
            return spareValue;
        }
        // Box and Muller, Ann. Math. Statist. 29, 610 (1958): two uniforms give two independent normals.
        double radius = std::sqrt(-2.0*std::log(uniform())), angle = 2.0*M_PI*uniform();
        spare = true;
        spareValue = radius*std::sin(angle);
        return radius*std::cos(angle);
    }
    /** The next uniform deviate in (0, 1), from 53 bits of two output words. */
    double uniform() {
        uint64_t high = word(), low = word();
        uint64_t bits = ((high << 32) | low) >> 11;
        return (bits + 0.5)*0x1.0p-53;
    }
private:
    uint32_t word() {
        if (used == 4) {
            block = philox4x32(counter, key);
            counter[3]++;
            used = 0;
        }
        return block[used++];
    }
    std::array<uint32_t, 2> key;
    std::array<uint32_t, 4> counter, block;
    int used;
    bool spare;
    double spareValue;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_NUMERICS_PHILOX_H_*/
