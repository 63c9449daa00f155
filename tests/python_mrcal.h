#pragma once
// The Python interpreter that can `import mrcal`, for the tests that check our
// files and fits against mrcal itself; "" when none is installed (they skip).
// Debian's python3-mrcal is installed for the system interpreter, which a
// python3 earlier on PATH (pyenv, a virtualenv) may hide; GLASSPIV_PYTHON first.
#include <cstdlib>
#include <string>
#include <vector>

namespace glasspiv::testing {

inline std::string python_with_mrcal() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("GLASSPIV_PYTHON")) candidates.emplace_back(env);
  candidates.insert(candidates.end(), {"python3", "/usr/bin/python3"});
  for (const std::string& python : candidates)
    if (std::system(("'" + python + "' -c 'import mrcal' >/dev/null 2>&1").c_str()) == 0) return python;
  return "";
}

}  // namespace glasspiv::testing
