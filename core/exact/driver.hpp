// The exact kernel's driver: the run's setup, the
// loop over segments (each searched by segment.hpp), the events applied between them and the
// run's end.  One body, exact_body<Regen>, instantiated twice in driver.cpp: a harmonic run
// and a cut (Regen a constant, so neither pays for the other's tests).
//
//   struct ExactRun                  the run's arrays and matrices, as views
//   run_exact(const ExactRun&)       the harmonic or the cut kernel; the time reached
#pragma once

#include "../arrays.hpp"

namespace bb::exact {

// One run: its arrays, its span, prepare's matrices (V is prepare's Vh, the halved
// eigenvectors; Vfull its V) and a cut's history step and tables.  The bindings check every
// shape before building one.
struct ExactRun {
    Vec p;
    Vec x;
    double t0 = 0.0, t_end = 0.0, t_steady = 0.0, rec_dt = 0.0;
    Mat rec, imp, stick, strobe;
    Vec met;
    CMat lam;
    CArr3 V, Vi;
    CMat Z;
    Mat D;
    CArr3 eh;
    double h = 0.0;
    Mat lvis;
    Vec cvis;
    CArr3 isum, Vfull;
    Span1<idx> kstep;
    CMat bq;
    idx nreg = 1;
    double dt_out = 0.0, hist_step = 0.0;
    CArr3 tabE;
    CArr4 tabP;
    Arr3 bnd;
    Span1<idx> levmax;
};

// Advances a.x exactly from a.t0 to a.t_end (the cut kernel if p[FORCING] is REGENERATIVE),
// with the outputs into a.rec, a.imp, a.stick, a.strobe and a.met; returns the time reached.
double run_exact(const ExactRun& a);

}  // namespace bb::exact
