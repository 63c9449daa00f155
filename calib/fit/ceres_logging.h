#pragma once
// Ceres logs through glog (warnings such as "Linear solver failure", errors such
// as "Residual and Jacobian evaluation failed", and glog's own "Logging before
// InitGoogleLogging" line) straight to stderr; the fits report through their
// results and InputError only. Every fit calls this before its first Solve.

namespace glasspiv {

// Raises glog's thresholds so that only FATAL (a crash anyway) is printed. Once
// per process; thread-safe.
void silence_ceres_logging();

}  // namespace glasspiv
