// oneDNN (Debian libdnnl-dev 2.6) on the same shapes, in its own preferred (blocked)
// layouts with no conversions timed: the library bar the issue sets for our kernels.
// Linked into benchmarks only, never into the library.
#pragma once
#include <string>

#include "benchmarks/kernels/shapes.h"

namespace yelan::bench {

// Milliseconds per call of `op` (conv2d.fwd, conv2d.bwd_data, conv2d.bwd_weights, and the
// deconv2d.* equivalents) with the current OpenMP thread count; < 0 if oneDNN is absent
// from this build or cannot express the shape.
double onednn_ms(const ConvCase& c, const std::string& op, int reps);
bool onednn_available();

}  // namespace yelan::bench
