// Seconds per stage of a command (see fpp/calib/time_split.hpp).

#include "fpp/calib/time_split.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace fpp::calib {

void TimeSplit::add(const std::string& stage, double seconds) {
    const auto found = std::find_if(stages_.begin(), stages_.end(),
                                    [&](const auto& s) { return s.first == stage; });
    if (found == stages_.end())
        stages_.emplace_back(stage, seconds);
    else
        found->second += seconds;
}

void TimeSplit::add(const TimeSplit& other) {
    for (const auto& [stage, seconds] : other.stages_)
        add(stage, seconds);
}

double TimeSplit::seconds(const std::string& stage) const {
    const auto found = std::find_if(stages_.begin(), stages_.end(),
                                    [&](const auto& s) { return s.first == stage; });
    return found == stages_.end() ? 0.0 : found->second;
}

std::string TimeSplit::summary() const {
    std::ostringstream s;
    s << std::fixed << std::setprecision(2);
    for (std::size_t k = 0; k < stages_.size(); ++k)
        s << (k ? ", " : "") << stages_[k].first << " " << stages_[k].second << " s";
    return s.str();
}

StageTimer::StageTimer(TimeSplit& split, std::string stage)
    : split_(split), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}

StageTimer::~StageTimer() {
    stop();
}

double StageTimer::stop() {
    if (!running_)
        return 0;
    running_ = false;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    split_.add(stage_, seconds);
    return seconds;
}

} // namespace fpp::calib
