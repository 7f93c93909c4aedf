// The scanner's log (fpp/scanner/log.hpp): one line per event on stderr,
// "level: message" on a terminal and systemd's "<priority>" prefix when
// stderr is the journal (JOURNAL_STREAM), a message's newlines folded into
// the one line; a sink taking the events instead.

#include "fpp/scanner/log.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

using fpp::scanner::Logger;
using fpp::scanner::LogLevel;

namespace {

// JOURNAL_STREAM set (or not) while it lives, as it was afterwards.
class JournalStream {
public:
    explicit JournalStream(bool set) {
        if (const char* v = std::getenv("JOURNAL_STREAM"))
            saved_ = v;
        if (set)
            ::setenv("JOURNAL_STREAM", "8:1234", 1);
        else
            ::unsetenv("JOURNAL_STREAM");
    }
    ~JournalStream() {
        if (saved_.empty())
            ::unsetenv("JOURNAL_STREAM");
        else
            ::setenv("JOURNAL_STREAM", saved_.c_str(), 1);
    }
    JournalStream(const JournalStream&) = delete;
    JournalStream& operator=(const JournalStream&) = delete;

private:
    std::string saved_;
};

// What `log` writes to stderr for one event of each level.
std::string stderr_of(const Logger& log) {
    testing::internal::CaptureStderr();
    log.error("camera 10.0.0.7: no answer");
    log.warning("button pressed 2 time(s) during the scan: ignored");
    log.info("scan-20240101-000000-000 written");
    log.log(LogLevel::debug, "flip 3 at 1.25 s");
    return testing::internal::GetCapturedStderr();
}

TEST(Log, OnATerminalEachLineStartsWithItsLevel) {
    const JournalStream none(false);
    const Logger log;
    EXPECT_EQ(stderr_of(log), "error: camera 10.0.0.7: no answer\n"
                              "warning: button pressed 2 time(s) during the scan: ignored\n"
                              "info: scan-20240101-000000-000 written\n"
                              "debug: flip 3 at 1.25 s\n");
}

TEST(Log, InTheJournalEachLineStartsWithItsSyslogPriority) {
    const JournalStream journal(true);
    const Logger log; // reads JOURNAL_STREAM when made
    EXPECT_EQ(stderr_of(log), "<3>camera 10.0.0.7: no answer\n"
                              "<4>button pressed 2 time(s) during the scan: ignored\n"
                              "<6>scan-20240101-000000-000 written\n"
                              "<7>flip 3 at 1.25 s\n");
}

TEST(Log, AMessageOfSeveralLinesIsOneEventOnOneLine) {
    const JournalStream none(false);
    const Logger log;
    testing::internal::CaptureStderr();
    log.error("cannot write the scan:\nNo space left on device\n");
    EXPECT_EQ(testing::internal::GetCapturedStderr(),
              "error: cannot write the scan: No space left on device \n");
}

TEST(Log, ASinkGetsEveryEventWithItsLevelAndWritesNothing) {
    std::vector<std::pair<LogLevel, std::string>> events;
    const Logger log(
        [&](LogLevel level, const std::string& message) { events.emplace_back(level, message); });
    testing::internal::CaptureStderr();
    log.error("e");
    log.warning("w\nsecond line");
    log.info("i");
    log.log(LogLevel::debug, "d");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    const std::vector<std::pair<LogLevel, std::string>> expected{
        {LogLevel::error, "e"},
        {LogLevel::warning, "w\nsecond line"},
        {LogLevel::info, "i"},
        {LogLevel::debug, "d"}};
    EXPECT_EQ(events, expected); // as given: folding lines is the stderr sink's
    // The levels are syslog's priorities.
    EXPECT_EQ(static_cast<int>(LogLevel::error), 3);
    EXPECT_EQ(static_cast<int>(LogLevel::warning), 4);
    EXPECT_EQ(static_cast<int>(LogLevel::info), 6);
    EXPECT_EQ(static_cast<int>(LogLevel::debug), 7);
}

TEST(Log, ALoggerWithoutASinkDropsEvents) {
    const Logger quiet{Logger::Sink{}};
    testing::internal::CaptureStderr();
    quiet.error("nobody hears this");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

} // namespace
