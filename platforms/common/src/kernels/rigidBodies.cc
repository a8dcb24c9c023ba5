/*
 * The stages of a rigid-body step on a common-compute platform (OpenCL, CUDA), in OpenMM's common
 * dialect. Compiled behind the numerics core (its common prelude, then numerics/core/Core*.h), so
 * the rotation of a drift, the Newton-Schulz re-orthonormalisation and the random streams are the
 * same functions the Reference and CPU platforms call (RigidBodyDynamics.cpp is the host twin of
 * every kernel here; the comments name its functions).
 *
 * Layout. Body b's particles are bodyParticles[bodyStart[b]] ... bodyParticles[bodyStart[b+1]-1]
 * (System indices), with bodyCoordinates (body frame, 3 doubles each) and bodyParticleMass parallel
 * to them. A particle's place in the platform's arrays (posq, velm, the force buffer) is
 * currentIndex[particle], rebuilt whenever the atoms are reordered. Each body's state is 18 doubles:
 * centre R, velocity V, angular momentum L (lab frame), attitude A (lab to body, row-major).
 *
 * Errors (an unstable simulation) are written once to errorCode/errorData (the first wins) and the
 * offending body or particle is left where it was; the host copies errorCode without waiting before
 * the step's last force evaluation and looks at it once that evaluation is queued.
 */

#define RIGID_STATE_SIZE 18
/* The threads of the one work group of rigidSumPairs (the host launches it with this many). */
#ifndef RIGID_SUM_THREADS
#define RIGID_SUM_THREADS 128
#endif
#define RIGID_ERROR_BODY_NOT_FINITE 1
#define RIGID_ERROR_BODY_MOVES 2
#define RIGID_ERROR_PARTICLE_MOVES 3

typedef struct {
    double r[3], v[3], l[3], a[3][3];
} RigidBodyState;

DEVICE void rigidLoadState(GLOBAL const double* RESTRICT states, int b, RigidBodyState* s) {
    int k, j;
    for (k = 0; k < 3; k++) {
        s->r[k] = states[RIGID_STATE_SIZE*b + k];
        s->v[k] = states[RIGID_STATE_SIZE*b + 3 + k];
        s->l[k] = states[RIGID_STATE_SIZE*b + 6 + k];
        for (j = 0; j < 3; j++)
            s->a[k][j] = states[RIGID_STATE_SIZE*b + 9 + 3*k + j];
    }
}

DEVICE void rigidStoreState(GLOBAL double* RESTRICT states, int b, const RigidBodyState* s) {
    int k, j;
    for (k = 0; k < 3; k++) {
        states[RIGID_STATE_SIZE*b + k] = s->r[k];
        states[RIGID_STATE_SIZE*b + 3 + k] = s->v[k];
        states[RIGID_STATE_SIZE*b + 6 + k] = s->l[k];
        for (j = 0; j < 3; j++)
            states[RIGID_STATE_SIZE*b + 9 + 3*k + j] = s->a[k][j];
    }
}

/* Positions in double: posq, plus posqCorrection in mixed precision (posqCorrection is not read otherwise). */
DEVICE void rigidReadPosition(GLOBAL const real4* posq, GLOBAL const real4* posqCorrection, int i, double* x) {
    real4 p = posq[i];
    x[0] = p.x;
    x[1] = p.y;
    x[2] = p.z;
#ifdef USE_MIXED_PRECISION
    real4 c = posqCorrection[i];
    x[0] += c.x;
    x[1] += c.y;
    x[2] += c.z;
#endif
}

/* The charge (posq.w) is kept. */
DEVICE void rigidWritePosition(GLOBAL real4* posq, GLOBAL real4* posqCorrection, int i, const double* x) {
    real4 p = posq[i];
    p.x = (real) x[0];
    p.y = (real) x[1];
    p.z = (real) x[2];
    posq[i] = p;
#ifdef USE_MIXED_PRECISION
    posqCorrection[i] = make_real4((real) (x[0] - (double) p.x), (real) (x[1] - (double) p.y), (real) (x[2] - (double) p.z), 0);
#endif
}

DEVICE void rigidReadVelocity(GLOBAL const mixed4* velm, int i, double* v) {
    mixed4 u = velm[i];
    v[0] = u.x;
    v[1] = u.y;
    v[2] = u.z;
}

/* The inverse mass (velm.w) is kept. */
DEVICE void rigidWriteVelocity(GLOBAL mixed4* velm, int i, const double* v) {
    mixed4 u = velm[i];
    u.x = (mixed) v[0];
    u.y = (mixed) v[1];
    u.z = (mixed) v[2];
    velm[i] = u;
}

/* The force on atom i from the fixed-point buffer (2^32 units, x|y|z blocks of paddedNumAtoms). */
DEVICE void rigidReadForce(GLOBAL const mm_long* force, int paddedNumAtoms, int i, double* f) {
    const double scale = 1.0/4294967296.0;
    f[0] = scale*force[i];
    f[1] = scale*force[i + paddedNumAtoms];
    f[2] = scale*force[i + 2*paddedNumAtoms];
}

DEVICE void rigidCross(const double* a, const double* b, double* c) {
    c[0] = a[1]*b[2] - a[2]*b[1];
    c[1] = a[2]*b[0] - a[0]*b[2];
    c[2] = a[0]*b[1] - a[1]*b[0];
}

/* w = a^T v */
DEVICE void rigidMultiplyVectorTransposed(double a[3][3], const double* v, double* w) {
    int i;
    for (i = 0; i < 3; i++)
        w[i] = a[0][i]*v[0] + a[1][i]*v[1] + a[2][i]*v[2];
}

/* The lab-frame arm A^T b_i of a body particle. */
DEVICE void rigidArm(RigidBodyState* s, GLOBAL const double* coordinates, int i, double* arm) {
    double x[3];
    x[0] = coordinates[3*i];
    x[1] = coordinates[3*i + 1];
    x[2] = coordinates[3*i + 2];
    rigidMultiplyVectorTransposed(s->a, x, arm);
}

/* The lab-frame angular velocity A^T I^-1 A L (RigidBodyDynamics::bodyAngularVelocity). */
DEVICE void rigidLabAngularVelocity(RigidBodyState* s, const RigidShape* shape, double* omega) {
    double bodyL[3], bodyOmega[3];
    rigidMultiplyVector(s->a, s->l, bodyL);
    rigidAngularVelocity(shape->moments, bodyL, bodyOmega);
    rigidMultiplyVectorTransposed(s->a, bodyOmega, omega);
}

DEVICE void rigidReportError(GLOBAL int* errorCode, GLOBAL double* errorData, int code, int index, double distance, double drift) {
#ifdef RIGID_OPENCL
    if (atomic_cmpxchg((volatile GLOBAL int*) errorCode, 0, code) == 0) {
#else
    if (atomicCAS(errorCode, 0, code) == 0) {
#endif
        errorData[0] = index;
        errorData[1] = distance;
        errorData[2] = drift;
    }
}

/* The particles of a body (start to end in bodyParticles) placed at R + A^T b_i. */
DEVICE void rigidPlaceParticles(RigidBodyState* s, GLOBAL const double* bodyCoordinates, GLOBAL const int* bodyParticles,
        GLOBAL const int* currentIndex, int start, int end, GLOBAL real4* posq, GLOBAL real4* posqCorrection) {
    double arm[3], x[3];
    int i, k;
    for (i = start; i < end; i++) {
        rigidArm(s, bodyCoordinates, i, arm);
        for (k = 0; k < 3; k++)
            x[k] = s->r[k] + arm[k];
        rigidWritePosition(posq, posqCorrection, currentIndex[bodyParticles[i]], x);
    }
}

/*
 * The centre-of-mass velocity V and the angular momentum l = sum m_i A^T b_i x (v_i - V) of a body's
 * particle velocities, taken to the body's momentum L = I' omega where its moments were raised
 * (rigidRaiseAngularMomentum with the body's three inertiaScale values; RigidBodyDynamics::projectBodyVelocities).
 */
DEVICE void rigidMomentaOfParticles(RigidBodyState* s, GLOBAL const double* bodyCoordinates, GLOBAL const int* bodyParticles,
        GLOBAL const double* bodyParticleMass, double mass, GLOBAL const int* currentIndex, int start, int end,
        GLOBAL const mixed4* velm, GLOBAL const double* inertiaScale, int b, double* com, double* l) {
    double arm[3], v[3], moment[3];
    int i, k;
    for (k = 0; k < 3; k++)
        com[k] = l[k] = 0.0;
    for (i = start; i < end; i++) {
        rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
        for (k = 0; k < 3; k++)
            com[k] += bodyParticleMass[i]*v[k];
    }
    for (k = 0; k < 3; k++)
        com[k] /= mass;
    for (i = start; i < end; i++) {
        rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
        rigidArm(s, bodyCoordinates, i, arm);
        for (k = 0; k < 3; k++)
            v[k] -= com[k];
        rigidCross(arm, v, moment);
        for (k = 0; k < 3; k++)
            l[k] += moment[k]*bodyParticleMass[i];
    }
    double scale[3] = {inertiaScale[3*b], inertiaScale[3*b + 1], inertiaScale[3*b + 2]};
    rigidRaiseAngularMomentum(s->a, scale, l);
}

/* The total force and the torque about the centre, sum A^T b_i x f_i, on a body. */
DEVICE void rigidForceAndTorque(RigidBodyState* s, GLOBAL const double* bodyCoordinates, GLOBAL const int* bodyParticles,
        GLOBAL const int* currentIndex, int start, int end, GLOBAL const mm_long* force, int paddedNumAtoms, double* total,
        double* torque) {
    double arm[3], f[3], t[3];
    int i, k;
    for (k = 0; k < 3; k++)
        total[k] = torque[k] = 0.0;
    for (i = start; i < end; i++) {
        rigidReadForce(force, paddedNumAtoms, currentIndex[bodyParticles[i]], f);
        rigidArm(s, bodyCoordinates, i, arm);
        rigidCross(arm, f, t);
        for (k = 0; k < 3; k++) {
            total[k] += f[k];
            torque[k] += t[k];
        }
    }
}

/* The rigid velocities v_i = V + omega x A^T b_i written to a body's particles, and recorded as written (as stored). */
DEVICE void rigidWriteRigidVelocities(RigidBodyState* s, const RigidShape* shape, GLOBAL const double* bodyCoordinates,
        GLOBAL const int* bodyParticles, GLOBAL const int* currentIndex, int start, int end, GLOBAL mixed4* velm,
        GLOBAL double* writtenVelocities) {
    double arm[3], omega[3], v[3];
    int i, k;
    rigidLabAngularVelocity(s, shape, omega);
    for (i = start; i < end; i++) {
        const int index = currentIndex[bodyParticles[i]];
        rigidArm(s, bodyCoordinates, i, arm);
        rigidCross(omega, arm, v);
        for (k = 0; k < 3; k++)
            v[k] += s->v[k];
        rigidWriteVelocity(velm, index, v);
        rigidReadVelocity(velm, index, v);  /* in single precision velm holds floats */
        writtenVelocities[3*i] = v[0];
        writtenVelocities[3*i + 1] = v[1];
        writtenVelocities[3*i + 2] = v[2];
    }
}

/* Not "distance > limit": a NaN distance fails too (RigidBodyDynamics::checkDisplacement). */
DEVICE int rigidDisplacementOk(double distance, double limit) {
    return distance <= limit && isfinite(distance);
}

/* currentIndex[atomIndex[i]] = i: where each System particle is now. */
KERNEL void rigidUpdateAtomOrder(int numAtoms, GLOBAL const int* RESTRICT atomIndex, GLOBAL int* RESTRICT currentIndex) {
    for (int i = GLOBAL_ID; i < numAtoms; i += GLOBAL_SIZE)
        currentIndex[atomIndex[i]] = i;
}

/* The velocities of the body particles as the kernels last wrote or read them (see rigidKickDrift). */
KERNEL void rigidRecordVelocities(int numBodyParticles, GLOBAL const int* RESTRICT bodyParticles,
        GLOBAL const int* RESTRICT currentIndex, GLOBAL const mixed4* RESTRICT velm, GLOBAL double* RESTRICT writtenVelocities) {
    for (int i = GLOBAL_ID; i < numBodyParticles; i += GLOBAL_SIZE) {
        double v[3];
        rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
        writtenVelocities[3*i] = v[0];
        writtenVelocities[3*i + 1] = v[1];
        writtenVelocities[3*i + 2] = v[2];
    }
}

/*
 * RigidBodyDynamics::kickAndDrift for the bodies bodyList[0 .. numBodies - 1]: the momenta rebuilt
 * from the particles if their velocities are not those last written (a CMMotionRemover changed them),
 * a kick of V += F kick / M, L += tau kick (none if kick is 0), the drift R += V drift with the free
 * rotation of the attitude (exact, or NO_SQUISH except for a linear body), and the particles placed
 * at R + A^T b_i (none of the three if drift is 0).
 */
KERNEL void rigidKickDrift(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyParticles,
        GLOBAL const double* RESTRICT bodyCoordinates, GLOBAL const double* RESTRICT bodyParticleMass,
        GLOBAL const double* RESTRICT bodyMass, GLOBAL const RigidShape* RESTRICT shapes, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL double* RESTRICT states, GLOBAL double* RESTRICT writtenVelocities, GLOBAL real4* posq, GLOBAL real4* posqCorrection,
        GLOBAL const mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms, double kick, double drift,
        int noSquish, double displacementLimit, GLOBAL int* errorCode, GLOBAL double* errorData,
        GLOBAL const double* RESTRICT inertiaScale, GLOBAL const int* RESTRICT bodyList) {
    for (int j = GLOBAL_ID; j < numBodies; j += GLOBAL_SIZE) {
        const int b = bodyList[j];
        RigidBodyState s;
        RigidShape shape = shapes[b];
        double v[3];
        int i, k;
        const int start = bodyStart[b], end = bodyStart[b + 1];
        const double mass = bodyMass[b];
        rigidLoadState(states, b, &s);
        /* RigidBodyDynamics::refreshMomenta */
        int changed = 0;
        for (i = start; i < end && !changed; i++) {
            rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
            changed = (v[0] != writtenVelocities[3*i] || v[1] != writtenVelocities[3*i + 1] || v[2] != writtenVelocities[3*i + 2]);
        }
        if (changed) {
            for (i = start; i < end; i++) {
                rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
                writtenVelocities[3*i] = v[0];
                writtenVelocities[3*i + 1] = v[1];
                writtenVelocities[3*i + 2] = v[2];
            }
            rigidMomentaOfParticles(&s, bodyCoordinates, bodyParticles, bodyParticleMass, mass, currentIndex, start, end, velm,
                    inertiaScale, b, s.v, s.l);
        }
        if (kick != 0.0) {
            double total[3], torque[3];
            rigidForceAndTorque(&s, bodyCoordinates, bodyParticles, currentIndex, start, end, force, paddedNumAtoms, total, torque);
            double nv[3], nl[3];
            for (k = 0; k < 3; k++) {
                nv[k] = s.v[k] + total[k]*(kick/mass);
                nl[k] = s.l[k] + torque[k]*kick;
            }
            if (!(isfinite(nv[0]*nv[0] + nv[1]*nv[1] + nv[2]*nv[2]) && isfinite(nl[0]*nl[0] + nl[1]*nl[1] + nl[2]*nl[2]))) {
                rigidReportError(errorCode, errorData, RIGID_ERROR_BODY_NOT_FINITE, b, 0.0, drift);
                continue;
            }
            for (k = 0; k < 3; k++) {
                s.v[k] = nv[k];
                s.l[k] = nl[k];
            }
        }
        if (drift != 0.0) {
            const double distance = sqrt(s.v[0]*s.v[0] + s.v[1]*s.v[1] + s.v[2]*s.v[2])*fabs(drift);
            if (!rigidDisplacementOk(distance, displacementLimit)) {
                rigidReportError(errorCode, errorData, RIGID_ERROR_BODY_MOVES, b, distance, drift);
                continue;
            }
            /* RigidBodyDynamics::driftBody and rotate */
            for (k = 0; k < 3; k++)
                s.r[k] += drift*s.v[k];
            if (shape.kind != RigidKindPoint) {
                double bodyL[3], omega[3];
                rigidMultiplyVector(s.a, s.l, bodyL);
                if (noSquish && shape.kind != RigidKindLinear)
                    rigidNoSquishRotate(shape.moments, drift, s.a, bodyL);
                else {
                    rigidAngularVelocity(shape.moments, bodyL, omega);
                    rigidRotorAdvance(&shape, omega, s.a, drift);
                }
                rigidReorthonormalize(s.a);
            }
            rigidPlaceParticles(&s, bodyCoordinates, bodyParticles, currentIndex, start, end, posq, posqCorrection);
        }
        rigidStoreState(states, b, &s);
    }
}

/*
 * RigidBodyDynamics::kickAndDrift for the free particles: v += f kick / m, then either the drift
 * x += v drift (no constraints) or posDelta = v drift for the constraint solver.
 */
KERNEL void rigidKickDriftFree(int numFree, GLOBAL const int* RESTRICT freeParticles, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL real4* posq, GLOBAL real4* posqCorrection, GLOBAL mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force,
        int paddedNumAtoms, double kick, double drift, double displacementLimit, int constrained, GLOBAL mixed4* RESTRICT posDelta,
        GLOBAL int* errorCode, GLOBAL double* errorData) {
    for (int j = GLOBAL_ID; j < numFree; j += GLOBAL_SIZE) {
        const int p = freeParticles[j];
        const int index = currentIndex[p];
        double v[3], f[3], x[3];
        int k;
        const double inverseMass = velm[index].w;
        rigidReadVelocity(velm, index, v);
        if (kick != 0.0) {
            rigidReadForce(force, paddedNumAtoms, index, f);
            for (k = 0; k < 3; k++)
                v[k] += f[k]*(kick*inverseMass);
            rigidWriteVelocity(velm, index, v);
        }
        const double distance = sqrt(v[0]*v[0] + v[1]*v[1] + v[2]*v[2])*fabs(drift);
        if (!rigidDisplacementOk(distance, displacementLimit)) {
            rigidReportError(errorCode, errorData, RIGID_ERROR_PARTICLE_MOVES, p, distance, drift);
            if (constrained)
                posDelta[index] = make_mixed4(0, 0, 0, 0);
            continue;
        }
        if (constrained)
            posDelta[index] = make_mixed4((mixed) (v[0]*drift), (mixed) (v[1]*drift), (mixed) (v[2]*drift), 0);
        else {
            rigidReadPosition(posq, posqCorrection, index, x);
            for (k = 0; k < 3; k++)
                x[k] += v[k]*drift;
            rigidWritePosition(posq, posqCorrection, index, x);
        }
    }
}

/*
 * After the constraint solver: the constrained displacement checked (the solver reports no failure,
 * and where it cannot meet the constraints it leaves non-finite or far-flung values), then
 * x += delta and v = delta / drift.
 */
KERNEL void rigidFinishFreeDrift(int numFree, GLOBAL const int* RESTRICT freeParticles, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL real4* posq, GLOBAL real4* posqCorrection, GLOBAL mixed4* RESTRICT velm, GLOBAL const mixed4* RESTRICT posDelta,
        double drift, double displacementLimit, GLOBAL int* errorCode, GLOBAL double* errorData) {
    for (int j = GLOBAL_ID; j < numFree; j += GLOBAL_SIZE) {
        const int p = freeParticles[j];
        const int index = currentIndex[p];
        const mixed4 delta = posDelta[index];
        double d[3] = {delta.x, delta.y, delta.z}, x[3], v[3];
        int k;
        const double distance = sqrt(d[0]*d[0] + d[1]*d[1] + d[2]*d[2]);
        if (!rigidDisplacementOk(distance, displacementLimit)) {
            rigidReportError(errorCode, errorData, RIGID_ERROR_PARTICLE_MOVES, p, distance, drift);
            continue;
        }
        rigidReadPosition(posq, posqCorrection, index, x);
        for (k = 0; k < 3; k++) {
            x[k] += d[k];
            v[k] = d[k]/drift;
        }
        rigidWritePosition(posq, posqCorrection, index, x);
        rigidWriteVelocity(velm, index, v);
    }
}

/*
 * RigidBodyDynamics::closingKick for the bodies: the last kick (none if 0), then the rigid
 * velocities v_i = V + omega x A^T b_i written to the particles (and recorded as written).
 */
KERNEL void rigidClosingKick(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyParticles,
        GLOBAL const double* RESTRICT bodyCoordinates, GLOBAL const double* RESTRICT bodyMass, GLOBAL const RigidShape* RESTRICT shapes,
        GLOBAL const int* RESTRICT currentIndex, GLOBAL double* RESTRICT states, GLOBAL double* RESTRICT writtenVelocities,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms, double kick) {
    for (int b = GLOBAL_ID; b < numBodies; b += GLOBAL_SIZE) {
        RigidBodyState s;
        RigidShape shape = shapes[b];
        int k;
        const int start = bodyStart[b], end = bodyStart[b + 1];
        rigidLoadState(states, b, &s);
        if (kick != 0.0) {
            double total[3], torque[3];
            rigidForceAndTorque(&s, bodyCoordinates, bodyParticles, currentIndex, start, end, force, paddedNumAtoms, total, torque);
            const double mass = bodyMass[b];
            for (k = 0; k < 3; k++) {
                s.v[k] += kick*total[k]/mass;
                s.l[k] += kick*torque[k];
            }
            rigidStoreState(states, b, &s);
        }
        rigidWriteRigidVelocities(&s, &shape, bodyCoordinates, bodyParticles, currentIndex, start, end, velm, writtenVelocities);
    }
}

/* The closing kick of the free particles, v += f kick / m (their velocity constraints follow). */
KERNEL void rigidKickFree(int numFree, GLOBAL const int* RESTRICT freeParticles, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force, int paddedNumAtoms, double kick) {
    for (int j = GLOBAL_ID; j < numFree; j += GLOBAL_SIZE) {
        const int index = currentIndex[freeParticles[j]];
        double v[3], f[3];
        int k;
        const double inverseMass = velm[index].w;
        rigidReadVelocity(velm, index, v);
        rigidReadForce(force, paddedNumAtoms, index, f);
        for (k = 0; k < 3; k++)
            v[k] += f[k]*(kick*inverseMass);
        rigidWriteVelocity(velm, index, v);
    }
}

/*
 * RigidBodyDynamics::thermalize: the exact Ornstein-Uhlenbeck step of each body's momenta with
 * damping c, its six deviates from NormalStream(seed, b, counter): three for V in the lab frame,
 * three for L drawn in the lab frame and taken into the principal frame, L_k <- c L_k +
 * sqrt((1 - c^2) I_k kT) xi_k.
 */
KERNEL void rigidThermalize(int numBodies, GLOBAL const double* RESTRICT bodyMass, GLOBAL const RigidShape* RESTRICT shapes,
        GLOBAL double* RESTRICT states, double c, double noise, RigidUInt64 seed, RigidUInt64 counter, GLOBAL double* RESTRICT energies) {
    for (int b = GLOBAL_ID; b < numBodies; b += GLOBAL_SIZE) {
        RigidBodyState s;
        RigidShape shape = shapes[b];
        RigidNormalStream normal;
        double xi[3], bodyL[3], bodyXi[3];
        int k;
        rigidLoadState(states, b, &s);
        rigidNormalStreamInitialize(&normal, seed, (RigidUInt32) b, counter);
        const double velocityNoise = noise/sqrt(bodyMass[b]);
        /* The heat, as RigidBodyDynamics::thermalize sums it: energies[2 b] translational, [2 b + 1] rotational. */
        double translational = -rigidTranslationalEnergy(bodyMass[b], s.v), rotational = 0.0;
        for (k = 0; k < 3; k++)
            s.v[k] = c*s.v[k] + velocityNoise*rigidNormalStreamNext(&normal);
        translational += rigidTranslationalEnergy(bodyMass[b], s.v);
        for (k = 0; k < 3; k++)
            xi[k] = rigidNormalStreamNext(&normal);
        if (shape.kind != RigidKindPoint) {
            rigidMultiplyVector(s.a, s.l, bodyL);
            rigidMultiplyVector(s.a, xi, bodyXi);
            rotational = -rigidRotationalEnergy(shape.moments, bodyL);
            for (k = 0; k < 3; k++)
                bodyL[k] = c*bodyL[k] + noise*sqrt(shape.moments[k])*bodyXi[k];
            rotational += rigidRotationalEnergy(shape.moments, bodyL);
            rigidMultiplyVectorTransposed(s.a, bodyL, s.l);
        }
        rigidStoreState(states, b, &s);
        energies[2*b] = translational;
        energies[2*b + 1] = rotational;
    }
}

/*
 * The free particles' Ornstein-Uhlenbeck step, deviates from NormalStream(seed, numBodies + j, counter);
 * energies[2 (numBodies + j)] = -(kinetic energy before), [2 (numBodies + j) + 1] = the kinetic energy
 * after (rigidFreeKineticEnergies writes it again after the velocity constraints, if any).
 */
KERNEL void rigidThermalizeFree(int numFree, int numBodies, GLOBAL const int* RESTRICT freeParticles,
        GLOBAL const int* RESTRICT currentIndex, GLOBAL mixed4* RESTRICT velm, double c, double noise, RigidUInt64 seed,
        RigidUInt64 counter, GLOBAL double* RESTRICT energies) {
    for (int j = GLOBAL_ID; j < numFree; j += GLOBAL_SIZE) {
        const int index = currentIndex[freeParticles[j]];
        RigidNormalStream normal;
        double v[3];
        int k;
        rigidNormalStreamInitialize(&normal, seed, (RigidUInt32) (numBodies + j), counter);
        const double velocityNoise = noise*sqrt((double) velm[index].w);
        rigidReadVelocity(velm, index, v);
        energies[2*(numBodies + j)] = -rigidTranslationalEnergy(1.0/velm[index].w, v);
        for (k = 0; k < 3; k++)
            v[k] = c*v[k] + velocityNoise*rigidNormalStreamNext(&normal);
        rigidWriteVelocity(velm, index, v);
        rigidReadVelocity(velm, index, v);
        energies[2*(numBodies + j) + 1] = rigidTranslationalEnergy(1.0/velm[index].w, v);
    }
}

/* energies[2 (numBodies + j) + 1] = the kinetic energy of free particle j now (after rigidThermalizeFree's velocity constraints). */
KERNEL void rigidFreeKineticEnergies(int numFree, int numBodies, GLOBAL const int* RESTRICT freeParticles,
        GLOBAL const int* RESTRICT currentIndex, GLOBAL const mixed4* RESTRICT velm, GLOBAL double* RESTRICT energies) {
    for (int j = GLOBAL_ID; j < numFree; j += GLOBAL_SIZE) {
        const int index = currentIndex[freeParticles[j]];
        double v[3];
        rigidReadVelocity(velm, index, v);
        energies[2*(numBodies + j) + 1] = rigidTranslationalEnergy(1.0/velm[index].w, v);
    }
}

/*
 * RigidBodyDynamics::scaleMomenta for the bodies: V, L and the body particles' velocities times
 * alpha = rescaling[0], the factor rigidSumPairs computed on the device.
 */
KERNEL void rigidScaleMomenta(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyParticles,
        GLOBAL const int* RESTRICT currentIndex, GLOBAL double* RESTRICT states, GLOBAL double* RESTRICT writtenVelocities,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const double* RESTRICT rescaling) {
    const double alpha = rescaling[0];
    for (int b = GLOBAL_ID; b < numBodies; b += GLOBAL_SIZE) {
        int i, k;
        for (k = 0; k < 3; k++) {
            states[RIGID_STATE_SIZE*b + 3 + k] *= alpha;
            states[RIGID_STATE_SIZE*b + 6 + k] *= alpha;
        }
        for (i = bodyStart[b]; i < bodyStart[b + 1]; i++) {
            const int index = currentIndex[bodyParticles[i]];
            double v[3];
            rigidReadVelocity(velm, index, v);
            for (k = 0; k < 3; k++)
                v[k] *= alpha;
            rigidWriteVelocity(velm, index, v);
            rigidReadVelocity(velm, index, v);
            writtenVelocities[3*i] = v[0];
            writtenVelocities[3*i + 1] = v[1];
            writtenVelocities[3*i + 2] = v[2];
        }
    }
}

KERNEL void rigidScaleFree(int numFree, GLOBAL const int* RESTRICT freeParticles, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL mixed4* RESTRICT velm, GLOBAL const double* RESTRICT rescaling) {
    const double alpha = rescaling[0];
    for (int j = GLOBAL_ID; j < numFree; j += GLOBAL_SIZE) {
        const int index = currentIndex[freeParticles[j]];
        double v[3];
        int k;
        rigidReadVelocity(velm, index, v);
        for (k = 0; k < 3; k++)
            v[k] *= alpha;
        rigidWriteVelocity(velm, index, v);
    }
}

/*
 * RigidBodyDynamics::computeKineticEnergies, per body and per free particle: energies[2 j] the
 * translational part (the centre of mass, or the free particle), energies[2 j + 1] the rest (for a
 * body with raised moments, sum L_k^2 / (2 I'_k) with L from rigidMomentaOfParticles).
 * Bodies take j = b, free particles j = numBodies + their index.
 */
KERNEL void rigidKineticEnergies(int numBodies, int numFree, GLOBAL const int* RESTRICT bodyStart,
        GLOBAL const int* RESTRICT bodyParticles, GLOBAL const double* RESTRICT bodyParticleMass, GLOBAL const double* RESTRICT bodyMass,
        GLOBAL const int* RESTRICT freeParticles, GLOBAL const int* RESTRICT currentIndex, GLOBAL const mixed4* RESTRICT velm,
        GLOBAL double* RESTRICT energies, GLOBAL const double* RESTRICT bodyCoordinates, GLOBAL const RigidShape* RESTRICT shapes,
        GLOBAL const double* RESTRICT inertiaScale, GLOBAL const double* RESTRICT states) {
    for (int j = GLOBAL_ID; j < numBodies + numFree; j += GLOBAL_SIZE) {
        double v[3];
        int i, k;
        if (j < numBodies) {
            double com[3] = {0.0, 0.0, 0.0}, rotational = 0.0;
            for (i = bodyStart[j]; i < bodyStart[j + 1]; i++) {
                rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
                for (k = 0; k < 3; k++)
                    com[k] += bodyParticleMass[i]*v[k];
            }
            for (k = 0; k < 3; k++)
                com[k] /= bodyMass[j];
            double scale[3] = {inertiaScale[3*j], inertiaScale[3*j + 1], inertiaScale[3*j + 2]};
            if (!rigidMomentsRaised(scale)) {
                for (i = bodyStart[j]; i < bodyStart[j + 1]; i++) {
                    rigidReadVelocity(velm, currentIndex[bodyParticles[i]], v);
                    for (k = 0; k < 3; k++)
                        v[k] -= com[k];
                    rotational += 0.5*bodyParticleMass[i]*(v[0]*v[0] + v[1]*v[1] + v[2]*v[2]);
                }
            }
            else {
                RigidBodyState s;
                RigidShape shape = shapes[j];
                double momentumCom[3], l[3], bodyL[3];
                rigidLoadState(states, j, &s);
                rigidMomentaOfParticles(&s, bodyCoordinates, bodyParticles, bodyParticleMass, bodyMass[j], currentIndex, bodyStart[j],
                        bodyStart[j + 1], velm, inertiaScale, j, momentumCom, l);
                rigidMultiplyVector(s.a, l, bodyL);
                rotational = rigidRotationalEnergy(shape.moments, bodyL);
            }
            energies[2*j] = 0.5*bodyMass[j]*(com[0]*com[0] + com[1]*com[1] + com[2]*com[2]);
            energies[2*j + 1] = rotational;
        }
        else {
            const int index = currentIndex[freeParticles[j - numBodies]];
            rigidReadVelocity(velm, index, v);
            energies[2*j] = 0.5*(v[0]*v[0] + v[1]*v[1] + v[2]*v[2])/velm[index].w;
            energies[2*j + 1] = 0.0;
        }
    }
}

/*
 * RigidBodyDynamics::computeKickedKineticEnergies, per body and per free particle (as
 * rigidKineticEnergies lays them out): each body's energy after a kick of its state's momenta by its
 * force and torque, in its own moments; each free particle's from velm, which the host has kicked
 * and projected onto the constraints.
 */
KERNEL void rigidKickedKineticEnergies(int numBodies, int numFree, GLOBAL const int* RESTRICT bodyStart,
        GLOBAL const int* RESTRICT bodyParticles, GLOBAL const double* RESTRICT bodyCoordinates, GLOBAL const double* RESTRICT bodyMass,
        GLOBAL const RigidShape* RESTRICT shapes, GLOBAL const int* RESTRICT freeParticles, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL const double* RESTRICT states, GLOBAL const mixed4* RESTRICT velm, GLOBAL const mm_long* RESTRICT force,
        int paddedNumAtoms, GLOBAL double* RESTRICT energies, double kick) {
    for (int j = GLOBAL_ID; j < numBodies + numFree; j += GLOBAL_SIZE) {
        double v[3];
        int k;
        if (j < numBodies) {
            RigidBodyState s;
            RigidShape shape = shapes[j];
            double total[3], torque[3], l[3], bodyL[3];
            rigidLoadState(states, j, &s);
            rigidForceAndTorque(&s, bodyCoordinates, bodyParticles, currentIndex, bodyStart[j], bodyStart[j + 1], force, paddedNumAtoms,
                    total, torque);
            const double mass = bodyMass[j];
            for (k = 0; k < 3; k++) {
                v[k] = s.v[k] + kick*total[k]/mass;
                l[k] = s.l[k] + kick*torque[k];
            }
            rigidMultiplyVector(s.a, l, bodyL);
            energies[2*j] = 0.5*mass*(v[0]*v[0] + v[1]*v[1] + v[2]*v[2]);
            energies[2*j + 1] = rigidRotationalEnergy(shape.moments, bodyL);
        }
        else {
            const int index = currentIndex[freeParticles[j - numBodies]];
            rigidReadVelocity(velm, index, v);
            energies[2*j] = 0.5*(v[0]*v[0] + v[1]*v[1] + v[2]*v[2])/velm[index].w;
            energies[2*j + 1] = 0.0;
        }
    }
}

/*
 * sums[0] = sum of values[2 j], sums[1] = sum of values[2 j + 1]: one work group of RIGID_SUM_THREADS
 * threads; then, by thread 0, as `mode` says:
 * - RIGID_SUM_RESCALE: the sums are the kinetic energy K (translation plus rotation) of a step of the
 *   Bussi thermostat, to which it applies rigidStochasticRescaling() with the deviates the host drew:
 *   rescaling[0] = alpha (which rigidScaleMomenta and rigidScaleFree read), [1] = K, [2] = K', and
 *   [3], the thermostat's work, += K' - K;
 * - RIGID_SUM_HEAT: the sums are the heat of rigidThermalize and rigidThermalizeFree: [3] += it;
 * - RIGID_SUM_TALLY: the sums are the kinetic energy K: [4] += sign K, [5] = K.
 * The sum it adds to starts from 0 if `restart` (the host has taken it).
 */
#define RIGID_SUM_PLAIN 0
#define RIGID_SUM_RESCALE 1
#define RIGID_SUM_HEAT 2
#define RIGID_SUM_TALLY 3
KERNEL void rigidSumPairs(int count, GLOBAL const double* RESTRICT values, GLOBAL double* RESTRICT sums, int mode,
        double targetKinetic, int dof, double c, double r1, double rest, int restart, GLOBAL double* RESTRICT rescaling, double sign) {
    LOCAL double first[RIGID_SUM_THREADS];
    LOCAL double second[RIGID_SUM_THREADS];
    double a = 0.0, b = 0.0;
    for (int j = LOCAL_ID; j < count; j += LOCAL_SIZE) {
        a += values[2*j];
        b += values[2*j + 1];
    }
    first[LOCAL_ID] = a;
    second[LOCAL_ID] = b;
    SYNC_THREADS;
    for (int step = RIGID_SUM_THREADS/2; step > 0; step /= 2) {
        if (LOCAL_ID < step) {
            first[LOCAL_ID] += first[LOCAL_ID + step];
            second[LOCAL_ID] += second[LOCAL_ID + step];
        }
        SYNC_THREADS;
    }
    if (LOCAL_ID == 0) {
        sums[0] = first[0];
        sums[1] = second[0];
        /* K as RigidBodyDynamics::rescaleMomenta sums it: translation + rotation */
        const double total = first[0] + second[0];
        if (mode == RIGID_SUM_RESCALE) {
            double newKinetic;
            rescaling[0] = rigidStochasticRescaling(total, targetKinetic, dof, c, r1, rest, &newKinetic);
            rescaling[1] = total;
            rescaling[2] = newKinetic;
            rescaling[3] = (restart ? 0.0 : rescaling[3]) + (newKinetic - total);
        }
        else if (mode == RIGID_SUM_HEAT)
            rescaling[3] = (restart ? 0.0 : rescaling[3]) + total;
        else if (mode == RIGID_SUM_TALLY) {
            rescaling[4] = (restart ? 0.0 : rescaling[4]) + sign*total;
            rescaling[5] = total;
        }
    }
}

/*
 * A projection without the host, for positions moved by a rigid translation of each body (a Monte
 * Carlo barostat moves every molecule by the scaled displacement of its centre): the centre moves by
 * the mass-weighted mean displacement of the body's particles from where the body had them, and the
 * particles are put at the moved rigid positions. A body whose particles moved otherwise than by one
 * translation (by more than `tolerance` nm) sets failed[0] and is left as it is: the host fits
 * every body then.
 */
KERNEL void rigidFitTranslation(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyParticles,
        GLOBAL const double* RESTRICT bodyCoordinates, GLOBAL const double* RESTRICT bodyParticleMass,
        GLOBAL const double* RESTRICT bodyMass, GLOBAL const int* RESTRICT currentIndex, GLOBAL double* RESTRICT states,
        GLOBAL real4* posq, GLOBAL real4* posqCorrection, double tolerance, GLOBAL int* failed) {
    for (int b = GLOBAL_ID; b < numBodies; b += GLOBAL_SIZE) {
        RigidBodyState s;
        double arm[3], x[3], shift[3] = {0.0, 0.0, 0.0};
        int i, k;
        const int start = bodyStart[b], end = bodyStart[b + 1];
        rigidLoadState(states, b, &s);
        for (i = start; i < end; i++) {
            rigidArm(&s, bodyCoordinates, i, arm);
            rigidReadPosition(posq, posqCorrection, currentIndex[bodyParticles[i]], x);
            for (k = 0; k < 3; k++)
                shift[k] += bodyParticleMass[i]*(x[k] - s.r[k] - arm[k]);
        }
        for (k = 0; k < 3; k++)
            shift[k] /= bodyMass[b];
        int rigid = isfinite(shift[0] + shift[1] + shift[2]);
        for (i = start; i < end && rigid; i++) {
            rigidArm(&s, bodyCoordinates, i, arm);
            rigidReadPosition(posq, posqCorrection, currentIndex[bodyParticles[i]], x);
            for (k = 0; k < 3; k++)
                rigid = rigid && fabs(x[k] - (s.r[k] + shift[k] + arm[k])) <= tolerance;
        }
        if (!rigid) {
            failed[0] = 1;
            continue;
        }
        for (k = 0; k < 3; k++)
            s.r[k] += shift[k];
        rigidPlaceParticles(&s, bodyCoordinates, bodyParticles, currentIndex, start, end, posq, posqCorrection);
        rigidStoreState(states, b, &s);
    }
}

/*
 * RigidBodyDynamics::projectVelocities: each body's particle velocities replaced by the rigid motion
 * with their linear and angular momentum about the body as it is placed, v_i = V + omega x A^T b_i,
 * and recorded as written. Nothing is done if failed[0] is set (rigidFitTranslation, launched
 * before, could not place every body: the host projects then); a non-finite momentum sets failed[1].
 */
KERNEL void rigidProjectVelocities(int numBodies, GLOBAL const int* RESTRICT bodyStart, GLOBAL const int* RESTRICT bodyParticles,
        GLOBAL const double* RESTRICT bodyCoordinates, GLOBAL const double* RESTRICT bodyParticleMass,
        GLOBAL const double* RESTRICT bodyMass, GLOBAL const RigidShape* RESTRICT shapes, GLOBAL const int* RESTRICT currentIndex,
        GLOBAL double* RESTRICT states, GLOBAL double* RESTRICT writtenVelocities, GLOBAL mixed4* RESTRICT velm,
        GLOBAL int* failed, GLOBAL const double* RESTRICT inertiaScale) {
    if (failed[0])
        return;
    for (int b = GLOBAL_ID; b < numBodies; b += GLOBAL_SIZE) {
        RigidBodyState s;
        RigidShape shape = shapes[b];
        double com[3], l[3];
        int k;
        const int start = bodyStart[b], end = bodyStart[b + 1];
        rigidLoadState(states, b, &s);
        rigidMomentaOfParticles(&s, bodyCoordinates, bodyParticles, bodyParticleMass, bodyMass[b], currentIndex, start, end, velm,
                inertiaScale, b, com, l);
        if (!isfinite(com[0] + com[1] + com[2] + l[0] + l[1] + l[2])) {
            failed[1] = 1;
            continue;
        }
        for (k = 0; k < 3; k++) {
            s.v[k] = com[k];
            s.l[k] = l[k];
        }
        rigidWriteRigidVelocities(&s, &shape, bodyCoordinates, bodyParticles, currentIndex, start, end, velm, writtenVelocities);
        rigidStoreState(states, b, &s);
    }
}
