#pragma once
// A request the scanner refuses, with the HTTP status that says why (409: a
// scan is running; 400: a bad value; ...). Thrown by the service and the
// API's handlers, answered as {"error": message}.
#include <stdexcept>
#include <string>

namespace fpp::scanner {

class ApiError : public std::runtime_error {
public:
    ApiError(int status, const std::string& message)
        : std::runtime_error(message), status_(status) {}
    int status() const { return status_; }

private:
    int status_;
};

} // namespace fpp::scanner
