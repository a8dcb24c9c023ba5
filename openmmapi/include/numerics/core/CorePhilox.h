/*
 * The numerics core, part 5: counter-based random numbers, the Philox4x32-10 generator of
 * J. K. Salmon, M. A. Moraes, R. O. Dror and D. E. Shaw, "Parallel random numbers: as easy as 1, 2, 3",
 * Proc. SC11 (2011), and standard normal deviates from it by the Box-Muller transform, so that a
 * kernel on any platform draws exactly the numbers the host draws for the same (seed, stream, step).
 * See numerics/RigidCore.h for the rules every core file follows (RigidUInt32 and RigidUInt64 are
 * the prelude's unsigned 32- and 64-bit integers).
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
#ifndef OPENMMRIGID_CORE_PHILOX_H_
#define OPENMMRIGID_CORE_PHILOX_H_

/** Philox4x32-10: the 4-word output block for a 4-word counter and a 2-word key (block may not alias them). */
RIGID_FUNCTION void rigidPhilox4x32(const RigidUInt32* counter, const RigidUInt32* key, RigidUInt32* block) {
    /* Salmon et al. (2011), Sec. 4.2: the multipliers and the Weyl key schedule of Philox4x32. */
    const RigidUInt32 multiplier0 = 0xD2511F53u, multiplier1 = 0xCD9E8D57u;
    const RigidUInt32 weyl0 = 0x9E3779B9u, weyl1 = 0xBB67AE85u;
    RigidUInt32 key0 = key[0], key1 = key[1];
    int round, k;
    for (k = 0; k < 4; k++)
        block[k] = counter[k];
    for (round = 0; round < 10; round++) {
        RigidUInt64 product0, product1;
        RigidUInt32 high0, low0, high1, low1;
        if (round > 0) {
            key0 += weyl0;
            key1 += weyl1;
        }
        product0 = (RigidUInt64) multiplier0*block[0];
        product1 = (RigidUInt64) multiplier1*block[2];
        high0 = (RigidUInt32) (product0 >> 32);
        low0 = (RigidUInt32) product0;
        high1 = (RigidUInt32) (product1 >> 32);
        low1 = (RigidUInt32) product1;
        block[0] = high1 ^ block[1] ^ key0;
        block[1] = low1;
        block[2] = high0 ^ block[3] ^ key1;
        block[3] = low0;
    }
}

/**
 * A stream of standard normal (and uniform) deviates for one (key, stream, step): block b of the
 * stream is the Philox output for the counter (stream, step low word, step high word, b). Streams with
 * different (stream, step) never share a counter, so their numbers are independent.
 */
typedef struct {
    RigidUInt32 key[2], counter[4], block[4];
    int used;        /* words of block already returned */
    int spare;       /* whether spareValue holds the second deviate of the last Box-Muller pair */
    double spareValue;
} RigidNormalStream;

RIGID_FUNCTION void rigidNormalStreamInitialize(RigidNormalStream* s, RigidUInt64 seed, RigidUInt32 stream, RigidUInt64 step) {
    int k;
    s->key[0] = (RigidUInt32) seed;
    s->key[1] = (RigidUInt32) (seed >> 32);
    s->counter[0] = stream;
    s->counter[1] = (RigidUInt32) step;
    s->counter[2] = (RigidUInt32) (step >> 32);
    s->counter[3] = 0;
    for (k = 0; k < 4; k++)
        s->block[k] = 0;
    s->used = 4;
    s->spare = 0;
    s->spareValue = 0.0;
}

/** The next 32-bit word of the stream. */
RIGID_FUNCTION RigidUInt32 rigidNormalStreamWord(RigidNormalStream* s) {
    if (s->used == 4) {
        rigidPhilox4x32(s->counter, s->key, s->block);
        s->counter[3]++;
        s->used = 0;
    }
    return s->block[s->used++];
}

/** The next uniform deviate in (0, 1), from 53 bits of two output words. */
RIGID_FUNCTION double rigidNormalStreamUniform(RigidNormalStream* s) {
    const RigidUInt64 high = rigidNormalStreamWord(s);
    const RigidUInt64 low = rigidNormalStreamWord(s);
    const RigidUInt64 bits = ((high << 32) | low) >> 11;
    return ((double) bits + 0.5)*0x1.0p-53;
}

/** The next standard normal deviate. */
RIGID_FUNCTION double rigidNormalStreamNext(RigidNormalStream* s) {
    double radius, angle;
    if (s->spare) {
        s->spare = 0;
        return s->spareValue;
    }
    /* Box and Muller, Ann. Math. Statist. 29, 610 (1958): two uniforms give two independent normals. */
    radius = sqrt(-2.0*log(rigidNormalStreamUniform(s)));
    angle = 2.0*rigidPi()*rigidNormalStreamUniform(s);
    s->spare = 1;
    s->spareValue = radius*sin(angle);
    return radius*cos(angle);
}

#endif /* OPENMMRIGID_CORE_PHILOX_H_ */
