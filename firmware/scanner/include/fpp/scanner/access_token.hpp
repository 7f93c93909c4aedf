#pragma once
// The API's bearer token: the first line of a file readable only by the
// scanner's user and group (the package makes a random one).
#include <filesystem>
#include <string>
#include <string_view>

namespace fpp::scanner {

// 16 to 256 printable ASCII characters without spaces; InputError naming the
// file otherwise, and when it cannot be read (missing, a folder).
std::string read_token_file(const std::filesystem::path& path);

// Whether the Authorization header is "Bearer <token>" (the scheme in any
// case, one space), the token compared in time that does not depend on
// where they differ.
bool authorized(std::string_view authorization, std::string_view token);

} // namespace fpp::scanner
