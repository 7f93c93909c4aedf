// The scanner's HTTP API (firmware/scanner/http-api.md) as a request reaches
// it from libmicrohttpd: Api::begin with the headers, then Api::handle with
// the body (kept in memory or spooled to a file, within the limit begin
// set), on a running ScannerService of the virtual scanner (the tiny rig:
// a scan takes milliseconds, so POST /scans really scans).
//
// Input: METHOD \n PATH \n AUTH \n CONTENT-TYPE \n BODY, where AUTH "T" is
// the right bearer token and anything else is sent as the Authorization
// header as it is. Every request must get a response: an exception out of
// the handler (which the server would turn into a 500 with its text) or a
// 500 is a finding, as is a crash or a sanitizer report.
#include "fpp/coefficient_table.hpp"
#include "fpp/scanner/api.hpp"
#include "fpp/scanner/api_events.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/event_hub.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/scanner_service.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "fpp/simulator/rig.hpp"
#include "fuzz_support.hpp"
#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"
#include "tiny_rig.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <thread>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;

namespace {

constexpr const char* kToken = "fuzz-token-0123456789abcdef";

// The scanner as its daemon runs it; made once, stopped at exit.
struct World {
    fs::path dir = fpp::fuzz::scratch() / "scanner";
    BoardConfig board;
    std::optional<SimBoard> sim;
    Logger log{[](LogLevel, const std::string&) {}};
    std::optional<Scanner> scanner;
    EventHub events;
    ApiEvents rendered{events};
    std::optional<ScannerService> service;
    std::optional<Api> api;
    std::atomic<bool> stop{false};
    std::thread loop;

    World() {
        fs::create_directories(dir);
        std::ofstream(dir / "rig.yaml") << sim::rig_to_yaml(fpp::test::tiny_rig());
        fpp::test::SimBoardYaml b;
        b.name = "fuzz-sim";
        b.store = dir / "scans";
        b.rig = dir / "rig.yaml";
        b.table = "table.fpt";
        b.max_mb = 4;
        b.binning = 1;
        std::ofstream(dir / "board.yaml") << b.text();
        board = read_board_config(dir / "board.yaml");
        sim.emplace(board);
        sim->limit_records(SimBoard::kDaemonRecordLimit);
        write_table(dir / "table.fpt", fpp::test::rig_truth_table(sim->rig()));
        scanner.emplace(board, sim->devices(), log);
        service.emplace(board, *scanner, sim->devices(), rendered, log,
                        ServiceOptions{dir / "table.fpt", std::nullopt, "", true});
        ApiOptions options;
        options.token = kToken;
        options.web_root = fs::path(FPP_SOURCE_DIR) / "firmware/scanner/web";
        options.three_root = "/usr/share/javascript/three";
        options.max_table_bytes = 64u * 100 * 75;
        api.emplace(*service, events, log, options);
        loop = std::thread([this] { service->run(ScanMode::scan, stop); });
    }
};

World& world() {
    static World* w = [] {
        auto* made = new World; // never freed: its thread runs until exit
        std::atexit([] {
            world().stop = true;
            world().loop.join();
        });
        return made;
    }();
    return *w;
}

// The next line of `text` from `pos` (without its '\n'); pos moves past it.
std::string next_line(const std::string& text, std::size_t& pos) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string line = text.substr(pos, end - pos);
    pos = std::min(end + 1, text.size());
    return line;
}

[[noreturn]] void finding(const std::string& what) {
    std::fprintf(stderr, "fuzz_http_api: %s\n", what.c_str());
    std::abort();
}

} // namespace

// The scanner is made before the first input, outside libFuzzer's per-input
// time limit (the truth table's fit takes seconds under the sanitizers).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
    (void)world();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    World& w = world();
    const std::string input = fpp::fuzz::as_text(data, size);
    std::size_t pos = 0;
    HttpRequest request;
    request.method = next_line(input, pos);
    request.path = next_line(input, pos);
    const std::string auth = next_line(input, pos);
    request.authorization = auth == "T" ? std::string("Bearer ") + kToken : auth;
    request.content_type = next_line(input, pos);
    const std::string body = input.substr(pos);

    const std::string what = request.method + " " + request.path;
    try {
        BodyPolicy policy;
        if (std::optional<HttpResponse> early = w.api->begin(request, policy)) {
            if (early->status >= 500)
                finding(what + ": begin answered " + std::to_string(early->status));
            return 0;
        }
        if (body.size() > policy.max_bytes)
            return 0; // the server answers 413 before the handler sees it
        request.body_bytes = body.size();
        int spool = -1;
        if (policy.spool_dir && !body.empty()) {
            std::string name = (*policy.spool_dir / ".upload-XXXXXX").string();
            spool = ::mkostemp(name.data(), O_CLOEXEC);
            if (spool < 0 ||
                ::write(spool, body.data(), body.size()) != static_cast<ssize_t>(body.size()))
                finding("cannot spool the body");
            ::close(spool);
            request.body_file = name;
        } else if (!body.empty()) {
            request.body = body;
        }
        HttpResponse response = w.api->handle(request);
        if (!request.body_file.empty())
            ::unlink(request.body_file.c_str());
        if (response.status >= 500 && response.status != 503 && response.status != 507)
            finding(what + ": " + std::to_string(response.status) + " " + response.body);
        // Streams (tar downloads) read to their end, as a client would; the
        // event stream never ends and is only dropped.
        // (A scan pruned while its tar is read ends the stream with an
        // IoError: the server then cuts the transfer, which the client sees.)
        if (response.stream && request.path.find("events") == std::string::npos) {
            char buffer[65536];
            std::size_t total = 0;
            fpp::fuzz::expect_declared_errors([&] {
                while (const std::size_t n = response.stream->read(buffer, sizeof buffer)) {
                    total += n;
                    if (total > (64u << 20))
                        finding(what + ": a stream of over 64 MiB");
                }
            });
        }
    } catch (const std::exception& e) {
        finding(what + ": " + e.what() + " escaped the handler");
    }
    return 0;
}
