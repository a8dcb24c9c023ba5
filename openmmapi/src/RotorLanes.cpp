/*
 * The one translation unit that instantiates the core's rigidRotorAdvanceLanes() for the library,
 * and the drift's correction of the attitudes after a rotation (reorthonormalizeAttitudes, the core's
 * rigidReorthonormalize inlined and vectorized here: 9 against 19 ns per attitude on the Intel Xeon
 * of 2026-12-04, bit for bit the same). CMakeLists.txt compiles it with options that change no value
 * the code computes but let GCC vectorize the loops over the lanes:
 * - -O3 (the project's default is -O2): the small fixed loops inside a lane loop (the 3 x 3 products)
 *   are unrolled before vectorization, which -O2 leaves as loops;
 * - -fno-math-errno: sqrt is the instruction alone, without the call that would set errno for a
 *   negative argument (there is none under the contract, and nothing reads errno);
 * - -fno-trapping-math: a comparison or an operation of a lane that the select then discards may be
 *   evaluated (no floating-point exception is observed anywhere);
 * - -fallow-store-data-races: "x = keep ? x : next", which GCC rewrites as a conditional store, may
 *   become a load, a select and a store. Every such store here is to the function's own local
 *   arrays, which no other thread sees;
 * - -fopenmp-simd: RIGID_LANE_LOOP below marks each loop over the lanes "omp simd".
 * - -ffp-contract=off: no multiply-add is fused, in the AVX2 version below either.
 * GCC builds the function twice on x86-64: for the baseline (SSE2, two lanes per instruction) and
 * for AVX2 (four), chosen at load time by the processor (target_clones). Vector instructions round
 * each element as the scalar ones do, so either gives rigidRotorAdvance()'s results bit for bit
 * (TestFreeRotor checks it on the processor it runs on). On the Intel Xeon of 2026-12-04 the AVX2
 * version took 210 ns per generic asymmetric body against 326 for rigidRotorAdvance, side by side,
 * once the core's own sine and cosine (rigidSinCos) let those loops vectorize too
 * (docs/results/free_rotor_cost.md, row "lanes").
 */
#if defined(__GNUC__) || defined(__clang__)
#define RIGID_LANE_LOOP _Pragma("omp simd")
#endif
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define RIGID_LANE_TARGETS __attribute__((target_clones("avx2", "default")))
#else
#define RIGID_LANE_TARGETS
#endif

#include "internal/RotorLanes.h"

namespace OpenMMRigid {

RIGID_LANE_TARGETS void advanceFreeRotors(int count, const RigidShape* shapes, double omega[][3], double attitude[][3][3], double t) {
    rigidRotorAdvanceLanes(count, shapes, omega, attitude, t);
}

RIGID_LANE_TARGETS void reorthonormalizeAttitudes(int count, double attitude[][3][3]) {
    for (int b = 0; b < count; b++)
        rigidReorthonormalize(attitude[b]);
}

} // namespace OpenMMRigid
