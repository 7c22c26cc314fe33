#include "reader/assertion_guard.hpp"

#include <csetjmp>
#include <cstdio>
#include <cstdlib>

namespace flutterscan::reader {
namespace {

/// Where a failed assertion in this thread returns to, if a guarded call is running.
thread_local sigjmp_buf* t_return_point = nullptr;
thread_local std::string t_failure;

}  // namespace

std::string run_catching_assertions(const std::function<void()>& call) {
  sigjmp_buf here;
  sigjmp_buf* const outer = t_return_point;
  t_failure.clear();
  if (sigsetjmp(here, 0) == 0) {
    t_return_point = &here;
    call();
    t_return_point = outer;
    return {};
  }
  t_return_point = outer;
  return t_failure;
}

}  // namespace flutterscan::reader

/// glibc's assertion handler (the signature of <assert.h>), replaced for the
/// whole process: within a guarded call it returns to the guard, otherwise it
/// prints glibc's message and aborts as glibc's does.
extern "C" [[noreturn]] void __assert_fail(const char* assertion, const char* file,
                                           unsigned int line, const char* function) noexcept {
  using namespace flutterscan::reader;
  if (sigjmp_buf* back = t_return_point) {
    t_failure = std::string(file) + ":" + std::to_string(line) + ": " + function + ": Assertion `" +
                assertion + "' failed";
    siglongjmp(*back, 1);
  }
  std::fprintf(stderr, "%s:%u: %s: Assertion `%s' failed.\n", file, line, function, assertion);
  std::fflush(stderr);
  std::abort();
}
