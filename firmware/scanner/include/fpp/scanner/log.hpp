#pragma once
// One line per event on stderr, in a form journald keeps: with systemd's
// "<N>" priority prefix when stderr is the journal (JOURNAL_STREAM set),
// "level: message" otherwise. Tests capture lines through a sink.
#include <functional>
#include <string>

namespace fpp::scanner {

enum class LogLevel { error = 3, warning = 4, info = 6, debug = 7 }; // syslog priorities

class Logger {
public:
    using Sink = std::function<void(LogLevel, const std::string&)>;
    Logger(); // stderr
    explicit Logger(Sink sink) : sink_(std::move(sink)) {}

    void log(LogLevel level, const std::string& message) const;
    void error(const std::string& m) const { log(LogLevel::error, m); }
    void warning(const std::string& m) const { log(LogLevel::warning, m); }
    void info(const std::string& m) const { log(LogLevel::info, m); }

private:
    Sink sink_;
};

} // namespace fpp::scanner
