#include "fpp/scanner/log.hpp"

#include "fpp/enum_names.hpp"

#include <cstdio>
#include <cstdlib>

namespace fpp::scanner {

namespace {
constexpr EnumName<LogLevel> kLogLevelNames[] = {
    {LogLevel::error, "error"},
    {LogLevel::warning, "warning"},
    {LogLevel::info, "info"},
    {LogLevel::debug, "debug"},
};

const char* level_name(LogLevel level) {
    return name_of(kLogLevelNames, level, "info");
}
} // namespace

Logger::Logger() {
    const bool journal = std::getenv("JOURNAL_STREAM") != nullptr;
    sink_ = [journal](LogLevel level, const std::string& message) {
        char prefix[16];
        if (journal)
            std::snprintf(prefix, sizeof prefix, "<%d>", static_cast<int>(level));
        else
            std::snprintf(prefix, sizeof prefix, "%s: ", level_name(level));
        std::string line(prefix);
        line.reserve(line.size() + message.size() + 1);
        for (char c : message)
            line += (c == '\n' ? ' ' : c); // one event, one line
        line += '\n';
        std::fputs(line.c_str(), stderr); // one write per line: lines do not interleave
    };
}

void Logger::log(LogLevel level, const std::string& message) const {
    if (sink_)
        sink_(level, message);
}

} // namespace fpp::scanner
