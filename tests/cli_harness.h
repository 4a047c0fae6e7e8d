// Runs the sphfem command as a user would, for the CLI tests: its exit code and what it
// printed on stdout and stderr together.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace sphfem::testing_cli {

struct Result {
  int code;
  std::string out;  // stdout and stderr together
};

// `env_prefix` (e.g. "env -u DISPLAY") runs before the binary.
inline Result cli(const std::string& args, const std::string& env_prefix = "") {
  const std::string cmd = env_prefix + " " + std::string(SPHFEM_CLI) + " " + args + " 2>&1";
  Result r{0, ""};
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), p)) r.out += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace sphfem::testing_cli
