#include "fpp/scanner/access_token.hpp"

#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <algorithm>

namespace fpp::scanner {

std::string read_token_file(const std::filesystem::path& path) {
    const std::string text = yaml_fields::read_text_file(path);
    std::string token = text.substr(0, text.find('\n'));
    if (!token.empty() && token.back() == '\r')
        token.pop_back();
    if (token.size() < 16 || token.size() > 256)
        throw InputError(path, "token", "must be 16 to 256 characters on the first line");
    for (const char c : token)
        if (c <= ' ' || c > '~')
            throw InputError(path, "token", "printable ASCII without spaces only");
    return token;
}

bool authorized(std::string_view authorization, std::string_view token) {
    // The scheme's name is case-insensitive (RFC 7235, 2.1): "bearer" too.
    constexpr std::string_view scheme = "bearer ";
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
    if (authorization.size() != scheme.size() + token.size() ||
        !std::equal(scheme.begin(), scheme.end(), authorization.begin(),
                    [&](char s, char a) { return s == lower(a); }))
        return false; // the length is not a secret: every token has its own
    const std::string_view given = authorization.substr(scheme.size());
    unsigned char differ = 0;
    for (std::size_t i = 0; i < token.size(); ++i)
        differ |= static_cast<unsigned char>(given[i] ^ token[i]);
    return differ == 0;
}

} // namespace fpp::scanner
