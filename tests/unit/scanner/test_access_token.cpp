// The API's bearer token (fpp/scanner/access_token.hpp): the token file's
// first line and its refusals naming the file, and the Authorization
// header's check (the scheme in any case, one space, the whole token).

#include "fpp/scanner/access_token.hpp"

#include "fpp/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

using fpp::scanner::authorized;
using fpp::scanner::read_token_file;
namespace fs = std::filesystem;

namespace {

const std::string kToken = "3f9c1e0b7a2d4c68"; // 16 characters, the shortest allowed

fs::path write(const fpp::test::TempDir& dir, const std::string& text) {
    const fs::path file = dir / "token";
    std::ofstream(file, std::ios::binary) << text;
    return file;
}

// The message of the InputError that reading `text` as a token file throws.
std::string refusal(const std::string& text) {
    fpp::test::TempDir dir;
    const fs::path file = write(dir, text);
    try {
        read_token_file(file);
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.file(), file);
        EXPECT_EQ(e.field(), "token");
        return std::string(e.what()).substr(file.string().size());
    }
    ADD_FAILURE() << "accepted a token file holding '" << text << "'";
    return "";
}

TEST(AccessToken, TheFirstLineIsTheToken) {
    fpp::test::TempDir dir;
    EXPECT_EQ(read_token_file(write(dir, kToken)), kToken);
    EXPECT_EQ(read_token_file(write(dir, kToken + "\n")), kToken);
    EXPECT_EQ(read_token_file(write(dir, kToken + "\r\n")), kToken); // written on Windows
    EXPECT_EQ(read_token_file(write(dir, kToken + "\nsecond line, ignored\n")), kToken);
    const std::string longest(256, '~');
    EXPECT_EQ(read_token_file(write(dir, longest + "\n")), longest);
    const std::string punctuation = "!\"#$%&'()*+,-./0123456789:;<=>?@[\\]^_`{|}";
    EXPECT_EQ(read_token_file(write(dir, punctuation)), punctuation);
}

TEST(AccessToken, RefusesATokenOfTheWrongLengthNamingTheFile) {
    const std::string length = ": token: must be 16 to 256 characters on the first line";
    EXPECT_EQ(refusal(""), length);
    EXPECT_EQ(refusal("\n" + kToken), length); // the token on the second line
    EXPECT_EQ(refusal(kToken.substr(1)), length);
    EXPECT_EQ(refusal(std::string(257, 'a')), length);
}

TEST(AccessToken, RefusesSpacesControlsAndNonAscii) {
    const std::string printable = ": token: printable ASCII without spaces only";
    EXPECT_EQ(refusal("3f9c1e0b 7a2d4c68"), printable);
    EXPECT_EQ(refusal("3f9c1e0b\t7a2d4c68"), printable);
    EXPECT_EQ(refusal(kToken + "\x7f"), printable);
    EXPECT_EQ(refusal(kToken + "\xc3\xa9"), printable); // UTF-8 of e acute
    // A CR ending the line is taken off (a file written on Windows), one only.
    EXPECT_EQ(refusal(kToken.substr(1) + "\r\n"),
              ": token: must be 16 to 256 characters on the first line");
    EXPECT_EQ(refusal(kToken + "\r\r\n"), printable);
}

TEST(AccessToken, AFileThatCannotBeReadIsRefusedNamingIt) {
    fpp::test::TempDir dir;
    const auto what = [](const fs::path& file) -> std::string {
        try {
            read_token_file(file);
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), file);
            EXPECT_EQ(e.field(), "");
            return e.what();
        }
        return "read";
    };
    EXPECT_EQ(what(dir / "absent"),
              (dir / "absent").string() + ": cannot open: No such file or directory");
    EXPECT_EQ(what(dir.path()), dir.path().string() + ": is a folder, not a file");
}

TEST(AccessToken, BearerSchemeInAnyCaseWithTheWholeToken) {
    EXPECT_TRUE(authorized("Bearer " + kToken, kToken));
    EXPECT_TRUE(authorized("bearer " + kToken, kToken));
    EXPECT_TRUE(authorized("BEARER " + kToken, kToken));
    EXPECT_TRUE(authorized("bEaReR " + kToken, kToken));
}

TEST(AccessToken, EverythingElseIsRefused) {
    EXPECT_FALSE(authorized("", kToken));
    EXPECT_FALSE(authorized(kToken, kToken));                   // no scheme
    EXPECT_FALSE(authorized("Bearer", kToken));                 // no token
    EXPECT_FALSE(authorized("Bearer  " + kToken, kToken));      // two spaces
    EXPECT_FALSE(authorized("Bearer\t" + kToken, kToken));      // not a space
    EXPECT_FALSE(authorized("Basic " + kToken, kToken));        // another scheme
    EXPECT_FALSE(authorized("Bearerx" + kToken, kToken));       // the space replaced
    EXPECT_FALSE(authorized("Bearer " + kToken + "0", kToken)); // longer
    EXPECT_FALSE(authorized("Bearer " + kToken.substr(1), kToken));
    // One character different, at the start, in the middle, at the end.
    for (const std::size_t at : {std::size_t(0), std::size_t(8), kToken.size() - 1}) {
        std::string other = kToken;
        other[at] = other[at] == 'x' ? 'y' : 'x';
        EXPECT_FALSE(authorized("Bearer " + other, kToken)) << at;
    }
    // The token's own case matters (only the scheme's does not).
    EXPECT_FALSE(authorized("Bearer 3F9C1E0B7A2D4C68", kToken));
}

} // namespace
