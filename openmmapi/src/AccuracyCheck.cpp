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
}

void AccuracyCheck::stateSet() {
    started = false;
    windowsAbove = 0;
    skipNext = true;
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

void AccuracyCheck::record(const Setting& now, double time, double shadowWork, double stepWork, double kinetic) {
    lastStepWork = stepWork;
    if (!message.empty())
        return;  // fired once: enough
    if (skipNext) {
        skipNext = false;
        return;
    }
    const bool changed = !(now == setting);
    if (changed)
        windowsAbove = 0;  // the windows in a row must be of one setting
    if (!started || changed) {
        // A new window: its origin is the step before the first one it holds.
        setting = now;
        started = true;
        startTime = time - now.stepSize;
        startWork = shadowWork - lastStepWork;
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
    lastTime = time;
    if (t >= WindowTime*(1.0 - 1e-9) && n >= MinimumSteps)
        closeWindow();
}

void AccuracyCheck::closeWindow() {
    started = false;
    const double sxx = stt - st*st/n, sxy = stw - st*sw/n, syy = sww - sw*sw/n;
    const double kineticVariance = skk/n - (sk/n)*(sk/n), meanKinetic = sk/n;
    if (!(sxx > 0.0) || setting.dof <= 0 || !(meanKinetic > 0.0))
        return;
    const double slope = sxy/sxx;  // shadow work per ps
    const double residual = max(0.0, syy - slope*sxy)/n;
    const double kT = (setting.temperature > 0.0 ? BOLTZ*setting.temperature : 2.0*meanKinetic/setting.dof);
    lastDrift = slope/(setting.dof*kT);
    bool above;
    stringstream text;
    text.precision(3);
    if (setting.friction > 0.0) {
        const double c = exp(-setting.friction*setting.stepSize);
        lastFigure = 2.0*slope*setting.stepSize/((1.0 - c*c)*setting.dof*kT);
        above = !(fabs(lastFigure) <= HeatingLimit);
        text << "the integration error heats the momenta the thermostat meets " << 100.0*lastFigure << " % above the bath "
                "(limit " << 100.0*HeatingLimit << " %; from the shadow work, " << lastDrift << " kT/ps per degree of freedom, "
                "over the " << WindowTime << " ps before t = " << lastTime << " ps)";
    }
    else {
        lastFigure = (kineticVariance > 0.0 ? sqrt(residual/kineticVariance) : 0.0);
        above = !(fabs(lastDrift) <= DriftLimit) || (setting.rescaling && !(lastFigure <= FluctuationLimit));
        text << "the energy error fluctuates " << lastFigure << " times as much as the kinetic energy";
        if (setting.rescaling)
            text << " (limit " << FluctuationLimit << ")";
        text << " and drifts " << lastDrift << " kT/ps per degree of freedom (limit " << DriftLimit << "), over the " <<
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
