#pragma once
// A real display seen by the simulated camera: every call goes to the
// display underneath (DRM/KMS on a board), and each flip event it delivers
// (the moment the pattern is on screen, on the board's clock) is noted, so
// that the virtual scanner's camera renders the pattern the projector really
// shows at its trigger time. For boards whose projector and lines are real
// and whose camera is simulated.
#include <cstdint>
#include <mutex>
#include <vector>

#include <fpp/drivers/display.hpp>
#include <fpp/sim/screen.hpp>

namespace fpp::sim {

class ObservedDisplay final : public drivers::Display, public Screen {
public:
    // `display` must outlive this object.
    explicit ObservedDisplay(drivers::Display& display);

    Size size() const override;
    void prepare(const std::vector<Image<std::uint8_t>>& patterns) override;
    void show(std::size_t index) override;
    drivers::FlipEvent wait_flip(std::chrono::milliseconds timeout) override;
    void restore() override;

    // The pattern of the latest flip event stamped at or before t_ns.
    int on_screen_at(std::int64_t t_ns) const override;
    const Image<std::uint8_t>& pattern(std::size_t index) const override;

private:
    drivers::Display& display_;
    std::vector<Image<std::uint8_t>> patterns_;
    mutable std::mutex mutex_; // flips_ may be read from a camera thread
    std::vector<drivers::FlipEvent> flips_;
};

} // namespace fpp::sim
