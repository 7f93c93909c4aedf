#pragma once
// Where a command's time goes: seconds per named stage, in the order the
// stages first ran. Poses may be processed on several threads at once, so a
// stage's seconds are summed over the threads that ran it: the stages of a
// command add up to more than its wall time when it ran them in parallel.

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace fpp::calib {

class TimeSplit {
public:
    void add(const std::string& stage, double seconds);
    // Every stage of `other`, in its order.
    void add(const TimeSplit& other);
    double seconds(const std::string& stage) const; // 0 for a stage that never ran
    const std::vector<std::pair<std::string, double>>& stages() const { return stages_; }
    // "reading 7.31 s, decoding 1.20 s, ..."
    std::string summary() const;

private:
    std::vector<std::pair<std::string, double>> stages_;
};

// Adds the time from its construction to its destruction, or to stop(), to
// a stage of a split.
class StageTimer {
public:
    StageTimer(TimeSplit& split, std::string stage);
    ~StageTimer();
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;
    // Ends the stage now; returns its seconds (0 when already stopped).
    double stop();

private:
    TimeSplit& split_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
    bool running_ = true;
};

} // namespace fpp::calib
