/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The numerics core run as OpenCL kernel source (CoreKernel.cl: the common   *
 * prelude, the core files and a drift kernel) on whatever OpenCL device is   *
 * present (PoCL on a CPU in the project's test machines), against the C++    *
 * API on the host: FreeRotor::advance for bodies of every kind and regime,   *
 * noSquishRotate, the first normal deviate of NormalStream, and the Bussi    *
 * thermostat's factor (rigidStochasticRescaling: generic, alpha < 0 by eq.   *
 * (A8), K <= 0, Kbar = 0, c = 1, N_f = 0; 1e-14 relative). Built only       *
 * where CMake finds OpenCL; exits with 77 (skipped) without a device.        *
 *                                                                            *
 * The device has its own libm and may contract products into fused          *
 * multiply-adds, so the agreement is to rounding, not to the last bit: 1e-12 *
 * relative in omega and absolute in A for rotations of up to 30 radians.     *
 * -------------------------------------------------------------------------- */

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include "numerics/FreeRotor.h"
#include "numerics/NoSquish.h"
#include "numerics/Philox.h"
#include "numerics/RigidCore.h"
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using namespace OpenMMRigid;

static void check(cl_int error, const char* what) {
    if (error != CL_SUCCESS)
        throw std::runtime_error(std::string(what) + " failed with OpenCL error " + std::to_string(error));
}

int main() {
    try {
        cl_uint numPlatforms = 0;
        if (clGetPlatformIDs(0, nullptr, &numPlatforms) != CL_SUCCESS || numPlatforms == 0) {
            std::cout << "no OpenCL platform: skipped" << std::endl;
            return 77;
        }
        std::vector<cl_platform_id> platforms(numPlatforms);
        check(clGetPlatformIDs(numPlatforms, platforms.data(), nullptr), "clGetPlatformIDs");
        cl_device_id device = nullptr;
        for (cl_platform_id platform : platforms)
            if (clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, nullptr) == CL_SUCCESS)
                break;
        if (device == nullptr) {
            std::cout << "no OpenCL device: skipped" << std::endl;
            return 77;
        }
        cl_int error;
        cl_context context = clCreateContext(nullptr, 1, &device, nullptr, nullptr, &error);
        check(error, "clCreateContext");
        cl_command_queue queue = clCreateCommandQueue(context, device, 0, &error);
        check(error, "clCreateCommandQueue");
        std::ifstream file(OPENMMRIGID_CORE_KERNEL);
        std::stringstream text;
        text << file.rdbuf();
        std::string source = text.str();
        const char* sources[] = {source.c_str()};
        cl_program program = clCreateProgramWithSource(context, 1, sources, nullptr, &error);
        check(error, "clCreateProgramWithSource");
        std::string options = std::string("-I ") + OPENMMRIGID_INCLUDE_DIR;
        if (clBuildProgram(program, 1, &device, options.c_str(), nullptr, nullptr) != CL_SUCCESS) {
            size_t size;
            clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size);
            std::string log(size, ' ');
            clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, &log[0], nullptr);
            throw std::runtime_error("the core does not build as OpenCL C:\n" + log);
        }
        cl_kernel kernel = clCreateKernel(program, "rotateBodies", &error);
        check(error, "clCreateKernel");

        // Bodies of every kind and regime.
        std::mt19937_64 rng(5);
        std::normal_distribution<double> normal;
        std::vector<Vector3> moments, omegas;
        for (int n = 0; n < 64; n++) {
            double a = 0.5 + 4.5*std::uniform_real_distribution<double>()(rng), b = a + 0.3 + n%5, c = b + 0.7;
            Vector3 kinds[5] = {{a, b, c}, {c, a, b}, {a, a, a}, {a, b, a}, {0, a, a}};
            moments.push_back(kinds[n%5]);
            omegas.push_back({normal(rng), normal(rng), normal(rng)});
        }
        for (double offset : {0.0, 1e-6, -1e-6, 1e-12}) {
            moments.push_back({1, 5, 9});
            omegas.push_back({3, 0.5, 1 + offset});   // on and near the separatrix
        }
        for (int axis = 0; axis < 3; axis++) {
            Vector3 omega = {1e-20, -1e-20, 0.0};
            omega[axis] = 1.7;
            moments.push_back({1, 2, 3});
            omegas.push_back(omega);                  // steady rotation about each axis
        }
        moments.push_back({1, 2, 3});
        omegas.push_back({0, 0, 0});
        const int numBodies = moments.size();
        std::vector<double> flatMoments, flatOmega, flatAttitude;
        std::vector<Matrix3> attitudes;
        for (int b = 0; b < numBodies; b++) {
            double q[4] = {normal(rng), normal(rng), normal(rng), normal(rng)};
            double s = std::sqrt(q[0]*q[0] + q[1]*q[1] + q[2]*q[2] + q[3]*q[3]);
            for (double& x : q)
                x /= s;
            Matrix3 a = {{{q[0]*q[0] + q[1]*q[1] - q[2]*q[2] - q[3]*q[3], 2*(q[1]*q[2] - q[0]*q[3]), 2*(q[1]*q[3] + q[0]*q[2])},
                          {2*(q[1]*q[2] + q[0]*q[3]), q[0]*q[0] - q[1]*q[1] + q[2]*q[2] - q[3]*q[3], 2*(q[2]*q[3] - q[0]*q[1])},
                          {2*(q[1]*q[3] - q[0]*q[2]), 2*(q[2]*q[3] + q[0]*q[1]), q[0]*q[0] - q[1]*q[1] - q[2]*q[2] + q[3]*q[3]}}};
            attitudes.push_back(a);
            for (int k = 0; k < 3; k++) {
                flatMoments.push_back(moments[b][k]);
                flatOmega.push_back(omegas[b][k]);
                for (int j = 0; j < 3; j++)
                    flatAttitude.push_back(a[k][j]);
            }
        }
        int failures = 0;
        double largest = 0.0, largestNoise = 0.0;
        for (int useNoSquish : {0, 1})
            for (double dt : {0.02, -0.7, 5.0}) {
                cl_mem momentBuffer = clCreateBuffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(double)*3*numBodies, flatMoments.data(), &error);
                cl_mem omegaBuffer = clCreateBuffer(context, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof(double)*3*numBodies, flatOmega.data(), &error);
                cl_mem attitudeBuffer = clCreateBuffer(context, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof(double)*9*numBodies, flatAttitude.data(), &error);
                cl_mem noiseBuffer = clCreateBuffer(context, CL_MEM_WRITE_ONLY, sizeof(double)*numBodies, nullptr, &error);
                cl_mem statusBuffer = clCreateBuffer(context, CL_MEM_WRITE_ONLY, sizeof(cl_int)*numBodies, nullptr, &error);
                check(error, "clCreateBuffer");
                cl_ulong seed = 12345, step = 99;
                check(clSetKernelArg(kernel, 0, sizeof(int), &numBodies), "clSetKernelArg");
                check(clSetKernelArg(kernel, 1, sizeof(cl_mem), &momentBuffer), "clSetKernelArg");
                check(clSetKernelArg(kernel, 2, sizeof(cl_mem), &omegaBuffer), "clSetKernelArg");
                check(clSetKernelArg(kernel, 3, sizeof(cl_mem), &attitudeBuffer), "clSetKernelArg");
                check(clSetKernelArg(kernel, 4, sizeof(double), &dt), "clSetKernelArg");
                check(clSetKernelArg(kernel, 5, sizeof(int), &useNoSquish), "clSetKernelArg");
                check(clSetKernelArg(kernel, 6, sizeof(cl_ulong), &seed), "clSetKernelArg");
                check(clSetKernelArg(kernel, 7, sizeof(cl_ulong), &step), "clSetKernelArg");
                check(clSetKernelArg(kernel, 8, sizeof(cl_mem), &noiseBuffer), "clSetKernelArg");
                check(clSetKernelArg(kernel, 9, sizeof(cl_mem), &statusBuffer), "clSetKernelArg");
                size_t global = numBodies;
                check(clEnqueueNDRangeKernel(queue, kernel, 1, nullptr, &global, nullptr, 0, nullptr, nullptr), "clEnqueueNDRangeKernel");
                std::vector<double> omega(3*numBodies), attitude(9*numBodies), noise(numBodies);
                std::vector<cl_int> status(numBodies);
                check(clEnqueueReadBuffer(queue, omegaBuffer, CL_TRUE, 0, sizeof(double)*omega.size(), omega.data(), 0, nullptr, nullptr), "read");
                check(clEnqueueReadBuffer(queue, attitudeBuffer, CL_TRUE, 0, sizeof(double)*attitude.size(), attitude.data(), 0, nullptr, nullptr), "read");
                check(clEnqueueReadBuffer(queue, noiseBuffer, CL_TRUE, 0, sizeof(double)*noise.size(), noise.data(), 0, nullptr, nullptr), "read");
                check(clEnqueueReadBuffer(queue, statusBuffer, CL_TRUE, 0, sizeof(cl_int)*status.size(), status.data(), 0, nullptr, nullptr), "read");
                for (cl_mem buffer : {momentBuffer, omegaBuffer, attitudeBuffer, noiseBuffer, statusBuffer})
                    clReleaseMemObject(buffer);
                for (int b = 0; b < numBodies; b++) {
                    // The host's result through the validating API.
                    RigidShape shape = FreeRotor::classify(moments[b]);
                    Vector3 w = omegas[b];
                    Matrix3 a = attitudes[b];
                    if (useNoSquish) {
                        Vector3 l, used = {shape.moments[0], shape.moments[1], shape.moments[2]};
                        for (int k = 0; k < 3; k++)
                            l[k] = shape.moments[k]*w[k];
                        noSquishRotate(used, dt, a, l);
                        for (int k = 0; k < 3; k++)
                            w[k] = (shape.moments[k] > 0.0 ? l[k]/shape.moments[k] : 0.0);
                    }
                    else
                        FreeRotor::advance(moments[b], w, a, dt);
                    double scale = std::max(1e-300, std::sqrt(w[0]*w[0] + w[1]*w[1] + w[2]*w[2]));
                    double worst = 0.0;
                    for (int k = 0; k < 3; k++) {
                        worst = std::max(worst, std::fabs(w[k] - omega[3*b + k])/scale);
                        for (int j = 0; j < 3; j++)
                            worst = std::max(worst, std::fabs(a[k][j] - attitude[9*b + 3*k + j]));
                    }
                    NormalStream stream(seed, b, step);
                    double noiseError = std::fabs(stream.next() - noise[b]);
                    largest = std::max(largest, worst);
                    largestNoise = std::max(largestNoise, noiseError);
                    if (status[b] != RigidStatusOk || !(worst <= 1e-12) || !(noiseError <= 1e-14)) {
                        std::cout << "body " << b << " (moments " << moments[b][0] << " " << moments[b][1] << " " << moments[b][2]
                                  << "), dt " << dt << ", NO_SQUISH " << useNoSquish << ": status " << status[b]
                                  << ", deviation " << worst << ", normal deviate deviation " << noiseError << std::endl;
                        failures++;
                    }
                }
            }
        clReleaseKernel(kernel);

        // The thermostat's factor in each regime, against the host's core.
        struct Case {
            double kinetic, target, c, r1, rest;
            int dof;
        };
        std::vector<Case> cases;
        for (int n = 0; n < 200; n++) {
            const int dof = 1 + (int) (std::uniform_real_distribution<double>(0, n%2 == 0 ? 10 : 3000)(rng));
            const double target = 0.5*dof*std::uniform_real_distribution<double>(0.01, 10)(rng);
            cases.push_back({target*std::exp(std::uniform_real_distribution<double>(-6, 2)(rng)), target,
                             std::uniform_real_distribution<double>(0, 1)(rng), 3*normal(rng),
                             (dof - 1)*std::uniform_real_distribution<double>(0.5, 1.5)(rng), dof});
        }
        for (int dof : {1, 4, 50})
            cases.push_back({0.01, 10.0*dof, 0.1, -1.5, 0.5*dof, dof});  // alpha < 0 (eq. (A8))
        cases.push_back({0.0, 5.0, 0.5, 0.7, 2.0, 6});   // K = 0
        cases.push_back({-2.0, 5.0, 0.5, 0.7, 2.0, 6});  // K < 0
        cases.push_back({3.0, 0.0, 0.3, 0.7, 2.0, 6});   // Kbar = 0: damping
        cases.push_back({3.0, 5.0, 1.0, 0.7, 2.0, 6});   // c = 1
        cases.push_back({3.0, 5.0, 0.5, 0.7, 2.0, 0});   // N_f = 0
        const int numCases = cases.size();
        std::vector<double> inputs;
        std::vector<cl_int> dofs;
        for (const Case& k : cases) {
            inputs.insert(inputs.end(), {k.kinetic, k.target, k.c, k.r1, k.rest});
            dofs.push_back(k.dof);
        }
        cl_kernel rescaling = clCreateKernel(program, "stochasticRescaling", &error);
        check(error, "clCreateKernel");
        cl_mem inputBuffer = clCreateBuffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(double)*inputs.size(), inputs.data(), &error);
        cl_mem dofBuffer = clCreateBuffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(cl_int)*dofs.size(), dofs.data(), &error);
        cl_mem outputBuffer = clCreateBuffer(context, CL_MEM_WRITE_ONLY, sizeof(double)*2*numCases, nullptr, &error);
        check(error, "clCreateBuffer");
        check(clSetKernelArg(rescaling, 0, sizeof(int), &numCases), "clSetKernelArg");
        check(clSetKernelArg(rescaling, 1, sizeof(cl_mem), &inputBuffer), "clSetKernelArg");
        check(clSetKernelArg(rescaling, 2, sizeof(cl_mem), &dofBuffer), "clSetKernelArg");
        check(clSetKernelArg(rescaling, 3, sizeof(cl_mem), &outputBuffer), "clSetKernelArg");
        size_t global = numCases;
        check(clEnqueueNDRangeKernel(queue, rescaling, 1, nullptr, &global, nullptr, 0, nullptr, nullptr), "clEnqueueNDRangeKernel");
        std::vector<double> outputs(2*numCases);
        check(clEnqueueReadBuffer(queue, outputBuffer, CL_TRUE, 0, sizeof(double)*outputs.size(), outputs.data(), 0, nullptr, nullptr), "read");
        for (cl_mem buffer : {inputBuffer, dofBuffer, outputBuffer})
            clReleaseMemObject(buffer);
        clReleaseKernel(rescaling);
        double largestRescaling = 0.0;
        int negative = 0;
        for (int n = 0; n < numCases; n++) {
            const Case& k = cases[n];
            double newKinetic;
            const double alpha = rigidStochasticRescaling(k.kinetic, k.target, k.dof, k.c, k.r1, k.rest, &newKinetic);
            const double deviation = std::max(std::fabs(outputs[2*n] - alpha)/std::fabs(alpha),
                                              std::fabs(outputs[2*n + 1] - newKinetic)/std::max(std::fabs(newKinetic), 1e-300));
            largestRescaling = std::max(largestRescaling, deviation);
            negative += (outputs[2*n] < 0.0);
            if (!(deviation <= 1e-14)) {
                std::cout << "thermostat case " << n << " (K " << k.kinetic << ", Kbar " << k.target << ", N_f " << k.dof << ", c " << k.c
                          << "): device alpha " << outputs[2*n] << ", K' " << outputs[2*n + 1] << "; host " << alpha << ", " << newKinetic
                          << std::endl;
                failures++;
            }
        }
        if (negative < 3) {
            std::cout << "the scalings through zero did not come out negative" << std::endl;
            failures++;
        }
        std::cout << numCases << " thermostat factors agree with the host: largest relative deviation " << largestRescaling << std::endl;
        clReleaseProgram(program);
        clReleaseCommandQueue(queue);
        clReleaseContext(context);
        if (failures > 0) {
            std::cout << failures << " cases differ" << std::endl;
            return 1;
        }
        std::cout << numBodies << " bodies x 6 drifts agree with the host: largest deviation " << largest
                  << " (omega relative, A absolute), normal deviates " << largestNoise << std::endl;
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}
