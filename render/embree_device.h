#pragma once
// The one Embree device of the process, shared by every BVH glasspiv builds
// (the scene index of the tracer, mesh solids). Created on first use,
// thread-safe, released at exit. No I/O.
#include <embree3/rtcore.h>

namespace glasspiv {

// Throws std::runtime_error (with Embree's message) if Embree cannot start.
RTCDevice embree_device();

// Throws std::runtime_error naming `what` if the device holds an error
// (Embree reports errors through the device, not through return values).
void check_embree(const char* what);

}  // namespace glasspiv
