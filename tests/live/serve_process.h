#pragma once
// `organsim serve` as a child process of a test: started with its output in
// files, its port (the tests ask for port 0, any free one) read from the line
// it prints, stopped by the session's end or by SIGINT. Every wait is bounded.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "tests/app/run_cli_test_util.h"

namespace organsim::test {

class ServeProcess {
 public:
  // Starts `organsim serve ARGS... --port 0` with stdout and stderr in `dir`.
  ServeProcess(const std::vector<std::string>& args, const std::filesystem::path& dir) : dir_(dir) {
    std::filesystem::create_directories(dir);
    std::vector<std::string> argv{ORGANSIM_EXE, "serve"};
    argv.insert(argv.end(), args.begin(), args.end());
    argv.push_back("--port");
    argv.push_back("0");
    pid_ = fork();
    if (pid_ == 0) {
      if (!freopen((dir / "stdout.txt").c_str(), "w", stdout) || !freopen((dir / "stderr.txt").c_str(), "w", stderr))
        _exit(126);
      std::vector<char*> c;
      for (std::string& a : argv) c.push_back(a.data());
      c.push_back(nullptr);
      execv(c[0], c.data());
      _exit(127);
    }
  }
  ~ServeProcess() {
    if (pid_ > 0 && exit_code_ == kRunning) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  // The port from "OpenIGTLink on 127.0.0.1:PORT", waiting up to `seconds`; 0 if it never came.
  int port(double seconds = 120) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      if (const int p = announced_port(stdout_text())) return p;
      if (exited()) return 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return 0;
  }
  // The PORT of "OpenIGTLink on ADDRESS:PORT" followed by another character
  // (the line written whole), 0 if there is none yet.
  static int announced_port(const std::string& out) {
    const std::string key = "OpenIGTLink on ";
    const size_t at = out.find(key);
    if (at == std::string::npos) return 0;
    const size_t colon = out.find(':', at + key.size());
    if (colon == std::string::npos) return 0;
    size_t end = colon + 1;
    while (end < out.size() && std::isdigit(static_cast<unsigned char>(out[end]))) ++end;
    if (end == colon + 1 || end == out.size()) return 0;
    return std::stoi(out.substr(colon + 1, end - colon - 1));
  }
  void interrupt() { kill(pid_, SIGINT); }
  // The exit code, waiting up to `seconds` (-1: killed after that).
  int wait(double seconds = 120) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!exited() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (!exited()) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      exit_code_ = -1;
    }
    return exit_code_;
  }
  std::string stdout_text() const { return slurp(dir_ / "stdout.txt"); }
  std::string stderr_text() const { return slurp(dir_ / "stderr.txt"); }

 private:
  static constexpr int kRunning = -1000;
  bool exited() {
    if (exit_code_ != kRunning) return true;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return false;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return true;
  }
  std::filesystem::path dir_;
  pid_t pid_ = -1;
  int exit_code_ = kRunning;
};

}  // namespace organsim::test
