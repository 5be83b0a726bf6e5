#include "skyloc/platform/signals.h"

#include <signal.h>

#include <cerrno>
#include <csignal>

namespace skyloc {
namespace {

volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_report = 0;

extern "C" void OnStopSignal(int) {
  g_stop = 1;
}
extern "C" void OnReportSignal(int) {
  g_report = 1;
}

Status Install(int signal_number, void (*handler)(int), const char* name) {
  struct sigaction action {};
  action.sa_handler = handler;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: blocking calls return EINTR
  if (::sigaction(signal_number, &action, nullptr) != 0)
    return Status::FromErrno(errno, "cannot install the %s handler", name);
  return Status::Ok();
}

}  // namespace

Status InstallSignalHandlers() {
  SKYLOC_TRY(Install(SIGINT, OnStopSignal, "SIGINT"));
  SKYLOC_TRY(Install(SIGTERM, OnStopSignal, "SIGTERM"));
  SKYLOC_TRY(Install(SIGHUP, OnStopSignal, "SIGHUP"));
  SKYLOC_TRY(Install(SIGUSR1, OnReportSignal, "SIGUSR1"));
  SKYLOC_TRY(Install(SIGPIPE, SIG_IGN, "SIGPIPE"));
  SKYLOC_TRY(Install(SIGXFSZ, SIG_IGN, "SIGXFSZ"));
  return Status::Ok();
}

bool StopRequested() {
  return g_stop != 0;
}

bool TakeReportRequest() {
  if (g_report == 0)
    return false;
  g_report = 0;
  return true;
}

void RequestStop() {
  g_stop = 1;
}

void ClearSignalFlags() {
  g_stop = 0;
  g_report = 0;
}

}  // namespace skyloc
