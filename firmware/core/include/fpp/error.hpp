#pragma once
// Errors for bad input. Every rejection names the file and the field so that a
// person can fix the input without reading our source.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace fpp {

class InputError : public std::runtime_error {
public:
    InputError(std::filesystem::path file, std::string field, const std::string& what)
        : std::runtime_error(format(file, field, what)), file_(std::move(file)),
          field_(std::move(field)) {}

    const std::filesystem::path& file() const { return file_; }
    const std::string& field() const { return field_; }

private:
    static std::string format(const std::filesystem::path& file, const std::string& field,
                              const std::string& what) {
        std::string s = file.string();
        if (!field.empty())
            s += ": " + field;
        return s + ": " + what;
    }

    std::filesystem::path file_;
    std::string field_;
};

// An operating-system failure while reading or writing a file (disk full,
// permission denied). Carries the path.
class IoError : public std::runtime_error {
public:
    IoError(const std::filesystem::path& file, const std::string& what)
        : std::runtime_error(file.string() + ": " + what) {}
};

} // namespace fpp
