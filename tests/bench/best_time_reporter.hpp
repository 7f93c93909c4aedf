#pragma once
// Console output as usual, and each benchmark's best real time per iteration
// over the repetitions (--benchmark_repetitions) for the ratio summaries the
// benchmarks print: on a shared machine the best run is the one least
// disturbed by other work. Looked up by the benchmark's full name (e.g.
// "BM_CopyInput/real_time") or by its function name ("BM_CopyInput").

#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <vector>

namespace fpp::bench {

class BestTimeReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs) {
            if (run.run_type != Run::RT_Iteration || run.iterations <= 0)
                continue;
            const double t = run.real_accumulated_time / static_cast<double>(run.iterations);
            keep(run.run_name.str(), t);
            keep(run.run_name.function_name, t);
        }
        ConsoleReporter::ReportRuns(runs);
    }
    // Seconds, or 0 if the benchmark did not run.
    double seconds(const std::string& name) const {
        const auto it = best_.find(name);
        return it == best_.end() ? 0.0 : it->second;
    }

private:
    void keep(const std::string& name, double t) {
        const auto [it, fresh] = best_.emplace(name, t);
        if (!fresh && t < it->second)
            it->second = t;
    }
    std::map<std::string, double> best_;
};

// Google Benchmark's main, keeping the best times in `reporter` for the
// summary printed after; false (after saying so) for an unknown argument.
inline bool run_benchmarks(int& argc, char** argv, BestTimeReporter& reporter) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return false;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return true;
}

} // namespace fpp::bench
