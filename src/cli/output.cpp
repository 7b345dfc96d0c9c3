// The text outputs of view and export: checked, locked, built under a temporary name, and that
// name removed if a signal ends the command (output_file.hpp has the rules).
#include "cli.hpp"

#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

namespace soadyn::cli {

namespace {

// the temporary files and locks a signal must remove; fixed buffers, as only async-signal-safe
// calls may touch them in the handler
constexpr int kMaxPaths = 4;
char g_paths[kMaxPaths][4096];

void on_signal(int signo) {
  for (auto& p : g_paths)
    if (p[0]) unlink(p);
  static const char msg[] = "soadyn: interrupted: nothing written (an existing output is unchanged)\n";
  if (write(2, msg, sizeof msg - 1) < 0) {
  }
  _exit(128 + signo);
}

void remember(const std::string& path) {
  if (path.empty()) return;
  for (auto& p : g_paths)
    if (!p[0]) {
      std::snprintf(p, sizeof p, "%s", path.c_str());
      return;
    }
}

void forget(const std::string& path) {
  for (auto& p : g_paths)
    if (!path.empty() && path == p) p[0] = '\0';
}

void install_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &sa, nullptr);
  signal(SIGXFSZ, SIG_IGN);  // a file-size limit is a write error (EFBIG), not a silent death
}

}  // namespace

std::vector<OutputTarget> check_outputs(const std::vector<std::pair<std::string, OutputKind>>& outputs,
                                        const std::vector<std::string>& inputs, bool force) {
  std::vector<OutputTarget> targets;
  for (size_t i = 0; i < outputs.size(); ++i) {
    const auto& [path, kind] = outputs[i];
    if (path.empty()) {
      targets.push_back(OutputTarget::New);
      continue;
    }
    for (size_t j = 0; j < i; ++j) {
      const std::string& other = outputs[j].first;
      std::error_code ec;
      if (!other.empty() && (other == path || (path != "-" && std::filesystem::equivalent(path, other, ec))))
        throw Error(path + ": named for two outputs (" + to_string(outputs[j].second) + " and " + to_string(kind) +
                    "); give each its own file");
    }
    targets.push_back(check_output_path(path, kind, inputs, force));
  }
  return targets;
}

TextWriter::TextWriter(const std::string& path, OutputTarget target) {
  install_handlers();
  if (target == OutputTarget::New || target == OutputTarget::Replace) {
    lock_ = std::make_unique<OutputLock>(path);
    remember(lock_->lock_path());
  }
  out_ = std::make_unique<TextOutput>(path, target);
  remember(out_->temporary());
}

TextWriter::~TextWriter() {
  if (out_) forget(out_->temporary());
  out_.reset();  // removes an uncommitted temporary file
  if (lock_) forget(lock_->lock_path());
}

void TextWriter::commit() {
  const std::string tmp = out_->temporary();
  out_->commit();
  forget(tmp);
}

}  // namespace soadyn::cli
