#include "render/embree_device.h"

#include <stdexcept>
#include <string>

namespace glasspiv {

namespace {

struct Device {
  RTCDevice handle = nullptr;
  // Threads are ours (std::thread over rows); Embree builds its BVHs with TBB.
  Device() : handle(rtcNewDevice("verbose=0")) {
    if (!handle) throw std::runtime_error("Embree: cannot create a device (error " +
                                          std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
  }
  ~Device() { rtcReleaseDevice(handle); }
};

}  // namespace

RTCDevice embree_device() {
  static const Device device;
  return device.handle;
}

void check_embree(const char* what) {
  const RTCError error = rtcGetDeviceError(embree_device());
  if (error != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("Embree: ") + what + " failed (error " +
                             std::to_string(static_cast<int>(error)) + ")");
}

}  // namespace glasspiv
