// How a kernel spreads its loops over threads. libgomp enters and leaves every parallel
// region through its team machinery even when the team is one thread, and leaving costs a
// futex system call (1.3 us a region on a virtual machine with page-table isolation; the
// `if` clause does not avoid it), while one-core inference runs about 300 kernels a tick,
// most of them stage 2's small convolutions. On two threads those small ones lose more to
// waking and joining the second thread than they gain. kernels/README.md, "Threads".
#pragma once
#include <omp.h>

#include <cstddef>

namespace yelan::kernels {
namespace {  // internal linkage: ISA variant files instantiate it with their own flags

// Below these a kernel's work runs on the caller alone, whatever the thread count: waking
// a second thread and joining it costs more than the half it would take over (stage 2's
// convolutions of 17 x 22 pixels ran slower on two threads than on one).
constexpr double kShareMinFlops = 8e6;             // ConvShape::flops(): 2 x multiply-adds
constexpr std::size_t kShareMinFloats = 1u << 18;  // memory-bound passes: floats read or written
inline bool worth_sharing(double flops) { return flops >= kShareMinFlops; }
inline bool worth_sharing_floats(std::size_t floats) { return floats >= kShareMinFloats; }

// on_threads(threads, body): body's `#pragma omp for` loops are orphaned worksharing
// constructs. With more than one thread asked, body runs inside a parallel region of that
// many and they share its iterations; with one, body is called directly and they run every
// iteration on the caller (an orphaned `omp for` outside a region binds to a team of one: no
// library round trip). Inside an enclosing parallel region a region is still opened (a
// nested team, of one unless nesting is on): a loop is never shared with the caller's team.
template <class Body>
inline void on_threads(int threads, Body&& body) {
  if (threads > 1 || omp_in_parallel()) {
#pragma omp parallel num_threads(threads > 1 ? threads : 1)
    body();
  } else {
    body();
  }
}

// The same on the threads in force where the work is worth sharing (share), else on one.
template <class Body>
inline void on_team(bool share, Body&& body) {
  on_threads(share ? omp_get_max_threads() : 1, body);
}

template <class Body>
inline void on_team(Body&& body) {
  on_threads(omp_get_max_threads(), body);
}

}  // namespace
}  // namespace yelan::kernels
