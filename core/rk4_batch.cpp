// A batch of harmonic RK4 runs in one call: the rows of P, x, met and the records, each
// advanced by the single-run kernel (rk4.cpp), one after the other, with the GIL
// released once for all of them.
//
// A lock-step kernel (every stage a loop over the runs, so that the runs' dependent
// stage chains overlap) was measured here at 35-42 ns per run-step against the single
// run's 15-17 ns (benchmarks/bench_batch.py): with the runs' values stored one after the
// other the loops over the runs stay scalar, and the single run's step map is already
// short.  Running the rows one after the other is therefore the faster batch, and a run
// of a batch is the run alone bit for bit by construction (tests/test_batch.py).
#include "rk4.hpp"

namespace bb::rk4 {

void run_batch(const BatchArgs& a) {
    const idx nx = a.x.n1;
    for (idx r = 0; r < a.P.n0; ++r) {
        RunArgs one;
        one.p = a.P.row(r);
        one.x = {a.x.row(r), nx};
        one.t0 = a.t0;
        one.dt = a.dt;
        one.n_steps = a.n_steps;
        one.steady_start = a.steady_start;
        one.rec_every = 0;
        one.rec = {nullptr, 0, L::REC_NCOL};
        one.imp = a.imp[r];
        one.stick = a.stick[r];
        one.strobe = a.strobe[r];
        one.met = {a.met.row(r), a.met.n1};
        one.buf = {nullptr, 0, 2};
        one.contact = {nullptr, 0, L::CONTACT_NCOL};  // a contact's rows are not kept
        run_single(one);
    }
}

}  // namespace bb::rk4
