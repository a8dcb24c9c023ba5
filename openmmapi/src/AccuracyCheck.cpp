#include "internal/AccuracyCheck.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <sstream>

using namespace std;

namespace OpenMMRigid {

namespace {

atomic<AccuracyCheck::Notifier> accuracyNotifier(nullptr);

} // namespace

void AccuracyCheck::setNotifier(Notifier notifier) {
    accuracyNotifier = notifier;
}

bool AccuracyCheck::notify(const string& text) {
    Notifier notifier = accuracyNotifier;
    if (notifier != nullptr)
        return notifier(text);
    cerr << "Warning: " << text << endl;
    return true;
}

void AccuracyCheck::restart() {
    started = false;
    stepsToSample = 0;
}

void AccuracyCheck::stateSet() {
    restart();
    windowsAbove = 0;
}

bool AccuracyCheck::wantsStep(const Setting& now, double time) {
    if (!message.empty())
        return false;
    if (!(now == setting) || (!inEpisode && time >= nextEpisode)) {
        inEpisode = true;
        windowsInEpisode = 0;
    }
    return inEpisode;
}

int AccuracyCheck::sampleStride(const Setting& now) {
    if (!(now.stepSize > 0.0))
        return 1;
    const double windowSteps = max((double) MinimumSteps, ceil(WindowTime/now.stepSize*(1.0 - 1e-9)));
    return max(1, (int) (windowSteps/SamplesPerWindow));
}

bool AccuracyCheck::wantsSample(const Setting& now) {
    if (!started || !(now == setting))
        stepsToSample = 0;  // a new window: its origin is the end of this step
    const bool sample = (stepsToSample <= 0);
    stepsToSample = (sample ? sampleStride(now) : stepsToSample) - 1;
    return sample;
}

void AccuracyCheck::record(const Setting& now, double time, double shadowWork, double kinetic) {
    if (!message.empty())
        return;  // fired once: enough
    const bool changed = !(now == setting);
    if (changed)
        windowsAbove = 0;  // the windows in a row must be of one setting
    if (!started || changed) {
        // A new window, from this sample.
        setting = now;
        started = true;
        startTime = time;
        startWork = shadowWork;
        n = st = stt = sw = sww = stw = sk = skk = 0.0;
    }
    const double t = time - startTime, w = shadowWork - startWork;
    n += 1;
    st += t;
    stt += t*t;
    sw += w;
    sww += w*w;
    stw += t*w;
    sk += kinetic;
    skk += kinetic*kinetic;
    if (t >= WindowTime*(1.0 - 1e-9) && t >= MinimumSteps*now.stepSize*(1.0 - 1e-9)) {
        closeWindow(time);
        // The next window starts from this sample.
        started = true;
        startTime = time;
        startWork = shadowWork;
        n = 1;
        st = stt = sw = sww = stw = 0.0;
        sk = kinetic;
        skk = kinetic*kinetic;
    }
}

void AccuracyCheck::closeWindow(double lastTime) {
    const double sxx = stt - st*st/n, sxy = stw - st*sw/n, syy = sww - sw*sw/n;
    const double kineticVariance = skk/n - (sk/n)*(sk/n), meanKinetic = sk/n;
    if (!(sxx > 0.0) || setting.dof <= 0 || !(meanKinetic > 0.0))
        return;
    const double slope = sxy/sxx;  // shadow work per ps
    const double residual = max(0.0, syy - slope*sxy)/n;
    const double kT = (setting.temperature > 0.0 ? BOLTZ*setting.temperature : 2.0*meanKinetic/setting.dof);
    const double drift = slope/(setting.dof*kT);
    double figure;
    bool above;
    stringstream text;
    text.precision(3);
    if (setting.friction > 0.0) {
        const double c = exp(-setting.friction*setting.stepSize);
        figure = 2.0*slope*setting.stepSize/((1.0 - c*c)*setting.dof*kT);
        above = !(fabs(figure) <= HeatingLimit);
        text << "the integration error heats the momenta the thermostat meets " << 100.0*figure << " % above the bath "
                "(limit " << 100.0*HeatingLimit << " %; from the shadow work, " << drift << " kT/ps per degree of freedom, "
                "over the " << WindowTime << " ps before t = " << lastTime << " ps)";
    }
    else {
        figure = (kineticVariance > 0.0 ? sqrt(residual/kineticVariance) : 0.0);
        above = !(fabs(drift) <= DriftLimit) || (setting.rescaling && !(figure <= FluctuationLimit));
        text << "the energy error fluctuates " << figure << " times as much as the kinetic energy";
        if (setting.rescaling)
            text << " (limit " << FluctuationLimit << ")";
        text << " and drifts " << drift << " kT/ps per degree of freedom (limit " << DriftLimit << "), over the " <<
                WindowTime << " ps before t = " << lastTime << " ps";
    }
    windowsAbove = (above ? windowsAbove + 1 : 0);
    windowsInEpisode++;
    if (windowsInEpisode >= 2 && windowsAbove == 0) {
        inEpisode = false;
        nextEpisode = lastTime + PauseTime;
    }
    if (windowsAbove >= 2) {
        stringstream head;
        head << setting.description << " at a step of " << 1000.0*setting.stepSize << " fs";
        if (setting.friction > 0.0)
            head << " and friction " << setting.friction << "/ps";
        message = head.str() + " has left its accurate range: " + text.str() + ". Its averages are biased. " + setting.remedies +
                "; setAccuracyCheck(False) turns this check off.";
        firedTime = lastTime;
    }
}

} // namespace OpenMMRigid
