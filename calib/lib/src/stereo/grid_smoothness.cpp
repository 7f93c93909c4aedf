// The camera grid's smoothness by cross-validation over the poses (see
// stereo_stages.hpp).

#include "stereo/stereo_stages.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace fpp::calib::detail {

double choose_camera_smoothness(const RigState& from, const std::vector<CornerObservation>& corners,
                                const std::vector<bool>& used_poses, const FreeParameters& free,
                                const GridRegularisation& reg, const StereoOptions& options,
                                ThreadPool& pool,
                                std::vector<std::pair<double, double>>& validation) {
    const auto say = [&](const std::string& line) {
        if (options.progress)
            options.progress(line);
    };
    const std::vector<double>& choices = options.camera_grid_smoothness_choices;
    std::vector<int> in_use;
    for (std::size_t i = 0; i < used_poses.size(); ++i)
        if (used_poses[i])
            in_use.push_back(static_cast<int>(i));
    if (in_use.size() < 6 || choices.size() == 1) {
        validation.clear();
        return choices.front();
    }
    const int folds = std::min<int>(5, static_cast<int>(in_use.size()) / 2);
    say("choosing the camera grid's smoothness: " + std::to_string(folds) +
        "-fold cross-validation over " + std::to_string(in_use.size()) + " poses");
    FreeParameters place;
    place.poses = place.camera_observations = true;
    place.camera_weight = free.camera_weight;
    // The held-out corners' RMS of each smoothness in `batch`: each
    // choice's folds are independent calibrations, all of them on the
    // pool's threads, summed in order afterwards.
    std::vector<double> tried, rms;
    const auto validate = [&](const std::vector<double>& batch) {
        const int trials = static_cast<int>(batch.size()) * folds;
        std::vector<AdjustmentOutcome> held(static_cast<std::size_t>(trials));
        pool.parallel_for(trials, 1, [&](int begin, int end, int) {
            for (int t = begin; t < end; ++t) {
                const int f = t % folds;
                GridRegularisation fold_reg = reg;
                fold_reg.camera_smoothness = batch[std::size_t(t / folds)];
                std::vector<bool> train = used_poses, test(used_poses.size(), false);
                for (std::size_t k = 0; k < in_use.size(); ++k)
                    if (int(k) % folds == f) {
                        train[std::size_t(in_use[k])] = false;
                        test[std::size_t(in_use[k])] = true;
                    }
                RigState trial = from;
                adjust(trial, corners, {}, train, free, fold_reg, options.max_iterations, nullptr,
                       &pool);
                held[std::size_t(t)] = adjust(trial, corners, {}, test, place, fold_reg,
                                              options.max_iterations, nullptr, &pool);
            }
        });
        for (std::size_t c = 0; c < batch.size(); ++c) {
            double sum = 0;
            int rows = 0;
            for (int f = 0; f < folds; ++f) {
                const AdjustmentOutcome& h = held[c * std::size_t(folds) + std::size_t(f)];
                sum += h.data_cost / place.camera_weight;
                rows += h.residuals;
            }
            tried.push_back(batch[c]);
            rms.push_back(std::sqrt(sum / std::max(rows, 1)));
            validation.emplace_back(batch[c], rms.back());
            std::ostringstream msg;
            msg.precision(4);
            msg << "  smoothness " << batch[c] << ": held-out poses' corners " << rms.back()
                << " px RMS per coordinate";
            say(msg.str());
        }
    };
    const auto best_choice = [&] {
        std::size_t best = 0;
        for (std::size_t k = 1; k < rms.size(); ++k)
            if (rms[k] < 0.98 * rms[best])
                best = k;
        return best;
    };
    validate(choices);
    // While the softest choice is still the best, ten times softer: a
    // lens whose defect the grid cannot follow at the listed choices
    // (a trefoil measured: 0.105, 0.061, 0.020 px from 1e4 to 100).
    for (int extra = 0;
         extra < options.camera_grid_softer_steps && best_choice() == tried.size() - 1; ++extra)
        validate({tried.back() / 10});
    return tried[best_choice()];
}

} // namespace fpp::calib::detail
