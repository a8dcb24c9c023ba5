/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * Cost of the exact free rotor (numerics/FreeRotor.h), in nanoseconds per    *
 * call, for each kind of body:                                               *
 *                                                                            *
 *   construct+evolve  a FreeRotor built from a new state and evolved once:   *
 *                     what an integrator pays for each body every step,      *
 *                     since every kick changes the angular momentum.         *
 *   evolve            one rotor evolved to many different times.             *
 *   advance           FreeRotor::advance: construct and evolve once, fused,  *
 *                     with the input checks.                                 *
 *   core-advance      rigidRotorAdvance, the core's unchecked entry point    *
 *                     with the body's RigidShape classified beforehand.      *
 *   lanes             advanceFreeRotors: the same for RigidLanes bodies at   *
 *                     once (the vectorized rigidRotorAdvanceLanes), per body:*
 *                     what the host platforms' drift calls.                  *
 *                                                                            *
 * Inputs (8192 random states per kind, and random times) are prepared in     *
 * advance and cycled through; every result is stored and summed into a      *
 * checksum afterwards, so nothing can be optimized away. Each repetition     *
 * times 131072 calls; the median of 9 repetitions is reported (after one     *
 * untimed warm-up). Run it on one core (python benchmarks/run.py             *
 * free_rotor_cost builds it and pins it with taskset). Optional arguments,   *
 * for a smoke run only: inputs per kind, calls per repetition, repetitions.  *
 *                                                                            *
 * Output: a human-readable table, then one machine-readable line per row:    *
 *   CSV,kind,mode,representation,median_ns,min_ns,max_ns,repetitions,calls   *
 * -------------------------------------------------------------------------- */

#include "internal/RotorLanes.h"
#include "numerics/FreeRotor.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

using namespace OpenMMRigid;

static int INPUTS = 8192;        // multiples of RigidLanes
static int CALLS = 131072;       // per repetition, >= 100k
static int REPETITIONS = 9;

struct Input {
    Vector3 moments, omega;
    Matrix3 attitude;
    double t;
};

struct Output {
    Vector3 omega;
    Matrix3 attitude;
};

struct Case {
    std::string kind;        // name of the row
    FreeRotor::Representation representation;
    std::vector<Input> inputs;
};

static std::mt19937_64 rng(145);

static double uniform(double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(rng);
}

static Matrix3 randomRotation() {
    std::normal_distribution<double> normal;
    double a = normal(rng), b = normal(rng), c = normal(rng), d = normal(rng);
    double n = std::sqrt(a*a + b*b + c*c + d*d);
    a /= n; b /= n; c /= n; d /= n;
    return {{{a*a + b*b - c*c - d*d, 2*(b*c - a*d), 2*(b*d + a*c)},
             {2*(b*c + a*d), a*a - b*b + c*c - d*d, 2*(c*d - a*b)},
             {2*(b*d - a*c), 2*(c*d + a*b), a*a - b*b - c*c + d*d}}};
}

/**
 * Random states of one kind, with angular velocities of order 1 and steps t of a typical MD size
 * (|omega| t around 0.01 to 0.1 rad). accept() filters asymmetric tops by their parameter m.
 */
static std::vector<Input> makeInputs(const std::function<Vector3()>& moments,
                                     const std::function<bool(const FreeRotor&)>& accept) {
    std::vector<Input> inputs;
    std::normal_distribution<double> normal;
    while ((int) inputs.size() < INPUTS) {
        Input in;
        in.moments = moments();
        in.omega = {normal(rng), normal(rng), normal(rng)};
        in.attitude = randomRotation();
        in.t = uniform(0.01, 0.1);
        if (accept(FreeRotor(in.moments, in.omega, in.attitude)))
            inputs.push_back(in);
    }
    return inputs;
}

static double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size()/2];
}

/** Runs body() (which makes CALLS calls) REPETITIONS times after a warm-up; ns per call of each repetition. */
static std::vector<double> time(const std::function<void()>& body) {
    body();
    std::vector<double> perCall;
    for (int r = 0; r < REPETITIONS; r++) {
        auto start = std::chrono::steady_clock::now();
        body();
        auto stop = std::chrono::steady_clock::now();
        perCall.push_back(std::chrono::duration<double, std::nano>(stop - start).count()/CALLS);
    }
    return perCall;
}

static double checksum(const std::vector<Output>& outputs) {
    double sum = 0.0;
    for (const Output& out : outputs)
        for (int i = 0; i < 3; i++) {
            sum += out.omega[i];
            for (int j = 0; j < 3; j++)
                sum += out.attitude[i][j];
        }
    return sum;
}

static const char* representationName(FreeRotor::Representation representation) {
    return representation == FreeRotor::ThetaSeries ? "theta-series" :
           representation == FreeRotor::EllipticIntegral ? "elliptic-integral" : "none";
}

int main(int argc, char** argv) {
    if (argc > 3) {
        INPUTS = std::max(1, std::atoi(argv[1])/RigidLanes)*RigidLanes;
        CALLS = std::max(1, std::atoi(argv[2])/RigidLanes)*RigidLanes;
        REPETITIONS = std::max(1, std::atoi(argv[3]));
    }
    auto anyRotor = [](const FreeRotor&) { return true; };
    auto parameterIn = [](double low, double high) {
        return [=](const FreeRotor& rotor) {
            return rotor.getKind() == FreeRotor::Asymmetric && rotor.getParameter() >= low && rotor.getParameter() <= high;
        };
    };
    auto asymmetricMoments = []() { return Vector3{uniform(1.0, 1.5), uniform(2.0, 2.5), uniform(3.0, 3.5)}; };
    std::vector<Case> cases;
    cases.push_back({"spherical", FreeRotor::Automatic,
                     makeInputs([]() { double a = uniform(1, 3); return Vector3{a, a, a}; }, anyRotor)});
    cases.push_back({"symmetric", FreeRotor::Automatic,
                     makeInputs([]() { double a = uniform(1, 2); return Vector3{a, a, uniform(2.5, 3.5)}; }, anyRotor)});
    cases.push_back({"asymmetric", FreeRotor::Automatic, makeInputs(asymmetricMoments, parameterIn(0.2, 0.8))});
    cases.push_back({"asymmetric-near-separatrix", FreeRotor::Automatic, makeInputs(asymmetricMoments, parameterIn(0.95, 0.9999))});
    cases.push_back({"asymmetric-at-separatrix", FreeRotor::Automatic, makeInputs(asymmetricMoments, parameterIn(0.99995, 1.0))});
    cases.push_back({"asymmetric-any-m", FreeRotor::Automatic, makeInputs(asymmetricMoments, parameterIn(0.0, 1.0))});
    cases.push_back({"asymmetric-elliptic-generic", FreeRotor::EllipticIntegral, makeInputs(asymmetricMoments, parameterIn(0.2, 0.8))});
    cases.push_back({"linear", FreeRotor::Automatic,
                     makeInputs([]() { double a = uniform(1, 3); return Vector3{a, a, 0.0}; }, anyRotor)});

    std::vector<Output> outputs(INPUTS);
    double total = 0.0;
    struct Row { std::string kind, mode, representation; std::vector<double> perCall; };
    std::vector<Row> rows;
    for (const Case& c : cases) {
        FreeRotor first(c.inputs[0].moments, c.inputs[0].omega, c.inputs[0].attitude, c.representation);
        std::string representation = representationName(first.getRepresentation());
        const Input* in = c.inputs.data();
        Output* out = outputs.data();
        auto constructAndEvolve = [&]() {
            for (int call = 0; call < CALLS; call++) {
                const Input& x = in[call%INPUTS];
                FreeRotor rotor(x.moments, x.omega, x.attitude, c.representation);
                rotor.evolve(x.t, out[call%INPUTS].omega, out[call%INPUTS].attitude);
            }
        };
        rows.push_back({c.kind, "construct+evolve", representation, time(constructAndEvolve)});
        total += checksum(outputs);
        if (c.representation == FreeRotor::Automatic) {
            // What RigidBodyIntegrator calls once per body and step (it skips the input checks; this does not).
            auto advance = [&]() {
                for (int call = 0; call < CALLS; call++) {
                    const Input& x = in[call%INPUTS];
                    Output& o = out[call%INPUTS];
                    o.omega = x.omega;
                    o.attitude = x.attitude;
                    FreeRotor::advance(x.moments, o.omega, o.attitude, x.t);
                }
            };
            rows.push_back({c.kind, "advance", representation, time(advance)});
            total += checksum(outputs);
            // The core's entry point, as the integrator calls it: the shape classified once per body.
            std::vector<RigidShape> shapes(INPUTS);
            for (int i = 0; i < INPUTS; i++)
                shapes[i] = FreeRotor::classify(in[i].moments);
            const RigidShape* shape = shapes.data();
            auto coreAdvance = [&]() {
                for (int call = 0; call < CALLS; call++) {
                    const Input& x = in[call%INPUTS];
                    Output& o = out[call%INPUTS];
                    double attitude[3][3];
                    o.omega = x.omega;
                    for (int i = 0; i < 3; i++)
                        for (int j = 0; j < 3; j++)
                            attitude[i][j] = x.attitude[i][j];
                    rigidRotorAdvance(&shape[call%INPUTS], o.omega.data(), attitude, x.t);
                    for (int i = 0; i < 3; i++)
                        for (int j = 0; j < 3; j++)
                            o.attitude[i][j] = attitude[i][j];
                }
            };
            rows.push_back({c.kind, "core-advance", representation, time(coreAdvance)});
            total += checksum(outputs);
            // The same, RigidLanes consecutive inputs per call, at the time of the first (INPUTS is a multiple of RigidLanes).
            auto lanes = [&]() {
                for (int call = 0; call < CALLS; call += RigidLanes) {
                    const int first = call%INPUTS;
                    double omega[RigidLanes][3], attitude[RigidLanes][3][3];
                    for (int lane = 0; lane < RigidLanes; lane++)
                        for (int i = 0; i < 3; i++) {
                            omega[lane][i] = in[first + lane].omega[i];
                            for (int j = 0; j < 3; j++)
                                attitude[lane][i][j] = in[first + lane].attitude[i][j];
                        }
                    advanceFreeRotors(RigidLanes, &shape[first], omega, attitude, in[first].t);
                    for (int lane = 0; lane < RigidLanes; lane++)
                        for (int i = 0; i < 3; i++) {
                            out[first + lane].omega[i] = omega[lane][i];
                            for (int j = 0; j < 3; j++)
                                out[first + lane].attitude[i][j] = attitude[lane][i][j];
                        }
                }
            };
            rows.push_back({c.kind, "lanes", representation, time(lanes)});
            total += checksum(outputs);
        }
        // Evolve only: one rotor, many different times spread over several rotation periods.
        std::vector<double> times(INPUTS);
        for (double& t : times)
            t = uniform(0.0, 20.0);
        const double* ts = times.data();
        auto evolveOnly = [&]() {
            for (int call = 0; call < CALLS; call++)
                first.evolve(ts[call%INPUTS], out[call%INPUTS].omega, out[call%INPUTS].attitude);
        };
        rows.push_back({c.kind, "evolve", representation, time(evolveOnly)});
        total += checksum(outputs);
    }

    std::printf("Free rotor cost, ns per call (median of %d repetitions x %d calls; %d distinct inputs per kind)\n\n",
                REPETITIONS, CALLS, INPUTS);
    std::printf("%-28s %-17s %-18s %10s %10s %10s\n", "kind", "mode", "representation", "median", "min", "max");
    for (const Row& row : rows)
        std::printf("%-28s %-17s %-18s %10.1f %10.1f %10.1f\n", row.kind.c_str(), row.mode.c_str(), row.representation.c_str(),
                    median(row.perCall), *std::min_element(row.perCall.begin(), row.perCall.end()),
                    *std::max_element(row.perCall.begin(), row.perCall.end()));
    std::printf("\nchecksum %.17g\n", total);
    std::printf("CSV,kind,mode,representation,median_ns,min_ns,max_ns,repetitions,calls\n");
    for (const Row& row : rows)
        std::printf("CSV,%s,%s,%s,%.2f,%.2f,%.2f,%d,%d\n", row.kind.c_str(), row.mode.c_str(), row.representation.c_str(),
                    median(row.perCall), *std::min_element(row.perCall.begin(), row.perCall.end()),
                    *std::max_element(row.perCall.begin(), row.perCall.end()), REPETITIONS, CALLS);
    return std::isfinite(total) ? 0 : 1;
}
