// The benchmark programs' main: Google Benchmark's own, except that the program fails (exit 1)
// when a benchmark reported an error (state.SkipWithError: a set-up that could not load its
// scene or rig, say) or when no benchmark matched the filter. BENCHMARK_MAIN exits 0 in both
// cases, so a broken benchmark's smoke test would pass.

#include <cstdio>
#include <cstring>
#include <vector>

#include <benchmark/benchmark.h>

namespace {

template <class Reporter>
class ErrorCounting final : public Reporter {
 public:
  void ReportRuns(const std::vector<benchmark::BenchmarkReporter::Run>& runs) override {
    for (const benchmark::BenchmarkReporter::Run& run : runs) {
      if (!run.error_occurred) continue;
      ++errors_;
      std::fprintf(stderr, "benchmark %s reported an error: %s\n", run.benchmark_name().c_str(), run.error_message.c_str());
    }
    Reporter::ReportRuns(runs);
  }
  int errors() const { return errors_; }

 private:
  int errors_ = 0;
};

template <class Reporter>
int run_with(Reporter& reporter) {
  const std::size_t ran = benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  if (reporter.errors() > 0) {
    std::fprintf(stderr, "%d benchmark run(s) reported an error\n", reporter.errors());
    return 1;
  }
  if (ran == 0) {
    std::fprintf(stderr, "no benchmark matched --benchmark_filter\n");
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // The display format, as --benchmark_format asks: console (the default) or json.
  const char* format = "console";
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--benchmark_format=", 19) == 0) format = argv[i] + 19;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  if (std::strcmp(format, "json") == 0) {
    ErrorCounting<benchmark::JSONReporter> reporter;
    return run_with(reporter);
  }
  ErrorCounting<benchmark::ConsoleReporter> reporter;
  return run_with(reporter);
}
