#include "calib/fit/ceres_logging.h"

#include <algorithm>
#include <mutex>

#include <glog/logging.h>

namespace glasspiv {

void silence_ceres_logging() {
  static std::once_flag once;
  std::call_once(once, [] {
    FLAGS_minloglevel = std::max<int>(FLAGS_minloglevel, google::GLOG_FATAL);
    FLAGS_stderrthreshold = std::max<int>(FLAGS_stderrthreshold, google::GLOG_FATAL);
    FLAGS_logtostderr = false;
    FLAGS_alsologtostderr = false;
  });
}

}  // namespace glasspiv
