// The HTTP API's route table (fpp/scanner/api_routes.hpp) against the
// endpoint list of firmware/scanner/http-api.md, both ways, and the path
// matching the routes are found by.

#include "test_support.hpp"

#include "fpp/scanner/api.hpp"
#include "fpp/scanner/api_routes.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>

namespace {

using fpp::scanner::Api;
using fpp::scanner::ApiRoute;
using Endpoint = std::pair<std::string, std::string>; // method, pattern

// Every "`METHOD /api/...`" the document names.
std::set<Endpoint> documented_endpoints() {
    std::ifstream in(fpp::test::source_dir() / "firmware" / "scanner" / "http-api.md");
    std::ostringstream text;
    text << in.rdbuf();
    const std::string doc = text.str();
    const std::regex endpoint("`(GET|HEAD|POST|PUT|PATCH|DELETE) (/api/[^` ]*)");
    std::set<Endpoint> found;
    for (auto it = std::sregex_iterator(doc.begin(), doc.end(), endpoint);
         it != std::sregex_iterator(); ++it)
        found.emplace((*it)[1].str(), (*it)[2].str());
    return found;
}

std::set<Endpoint> routed_endpoints() {
    std::set<Endpoint> routed;
    for (const ApiRoute& r : Api::routes())
        routed.emplace(std::string(r.method), std::string(r.pattern));
    return routed;
}

std::string joined(const std::set<Endpoint>& endpoints) {
    std::string s;
    for (const auto& [method, pattern] : endpoints)
        s += "  " + method + " " + pattern + "\n";
    return s;
}

TEST(ApiRoutes, EveryDocumentedEndpointIsRouted) {
    const std::set<Endpoint> documented = documented_endpoints();
    ASSERT_GT(documented.size(), 20u) << "http-api.md not found or its list not recognised";
    std::set<Endpoint> missing;
    for (const Endpoint& e : documented)
        if (!routed_endpoints().contains(e))
            missing.insert(e);
    EXPECT_TRUE(missing.empty()) << "documented in http-api.md but not routed:\n"
                                 << joined(missing);
}

TEST(ApiRoutes, EveryRouteIsDocumented) {
    const std::set<Endpoint> documented = documented_endpoints();
    std::set<Endpoint> missing;
    for (const Endpoint& e : routed_endpoints())
        if (!documented.contains(e))
            missing.insert(e);
    EXPECT_TRUE(missing.empty()) << "routed but not in http-api.md:\n" << joined(missing);
}

TEST(ApiRoutes, EachMethodAndPatternOnceAndNoTwoPatternsMatchOnePath) {
    const auto routes = Api::routes();
    EXPECT_EQ(routed_endpoints().size(), routes.size());
    // The dispatch takes the first matching pattern's parameters: a path that
    // two different patterns match would be ambiguous.
    for (const ApiRoute& a : routes) {
        std::string example(a.pattern);
        example = std::regex_replace(example, std::regex("\\{name\\}"), "s1");
        example = std::regex_replace(example, std::regex("\\{id\\}"), "scan-20260101-000000-000");
        const auto parts = fpp::scanner::split_path(example);
        EXPECT_TRUE(fpp::scanner::route_matches(a.pattern, parts)) << a.pattern;
        for (const ApiRoute& b : routes) {
            if (b.pattern != a.pattern) {
                EXPECT_FALSE(fpp::scanner::route_matches(b.pattern, parts))
                    << example << " matches " << a.pattern << " and " << b.pattern;
            }
        }
    }
}

TEST(ApiRoutes, PathsMatchSegmentBySegment) {
    using fpp::scanner::route_matches;
    using fpp::scanner::split_path;
    EXPECT_EQ(split_path("/api/v1//scans/"), (std::vector<std::string>{"api", "v1", "scans"}));
    EXPECT_TRUE(route_matches("/api/v1/scans/{id}", split_path("/api/v1/scans/anything")));
    EXPECT_FALSE(route_matches("/api/v1/scans/{id}", split_path("/api/v1/scans")));
    EXPECT_FALSE(route_matches("/api/v1/scans/{id}", split_path("/api/v1/scans/a/b")));
    EXPECT_FALSE(route_matches("/api/v1/status", split_path("/api/v1/STATUS")));
}

} // namespace
