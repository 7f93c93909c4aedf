// The enum <-> name tables (fpp/enum_names.hpp): name_of, value_of and
// names_list on a table of their own, then every value of the core's enums:
// named, read back from its name, and named once (the check a switch's
// -Wswitch gave before the tables).

#include "fpp/capture_set.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/enum_names.hpp"
#include "fpp/image_io.hpp"
#include "fpp/pattern_block.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

enum class Colour { red = 1, green = 2, light_blue = 7 };
constexpr fpp::EnumName<Colour> kColourNames[] = {
    {Colour::red, "red"},
    {Colour::green, "green"},
    {Colour::light_blue, "light-blue"},
};

enum class Single { only };
constexpr fpp::EnumName<Single> kSingleNames[] = {{Single::only, "only"}};

// At compile time too: the tables are constexpr.
static_assert(fpp::name_of(kColourNames, Colour::green)[0] == 'g');
static_assert(fpp::value_of(kColourNames, "light-blue") == Colour::light_blue);
static_assert(!fpp::value_of(kColourNames, "blue").has_value());

TEST(EnumNames, NameOfAValue) {
    EXPECT_STREQ(fpp::name_of(kColourNames, Colour::red), "red");
    EXPECT_STREQ(fpp::name_of(kColourNames, Colour::light_blue), "light-blue");
}

TEST(EnumNames, NameOfAValueNotInTheTableIsTheFallback) {
    const auto stray = static_cast<Colour>(3);
    EXPECT_STREQ(fpp::name_of(kColourNames, stray), "?");
    EXPECT_STREQ(fpp::name_of(kColourNames, stray, "unknown"), "unknown");
    // A fallback is only for values not in the table.
    EXPECT_STREQ(fpp::name_of(kColourNames, Colour::green, "unknown"), "green");
}

TEST(EnumNames, ValueOfAName) {
    EXPECT_EQ(fpp::value_of(kColourNames, "red"), Colour::red);
    EXPECT_EQ(fpp::value_of(kColourNames, std::string("green")), Colour::green);
    EXPECT_EQ(fpp::value_of(kColourNames, "light-blue"), Colour::light_blue);
}

TEST(EnumNames, ValueOfAnUnknownNameIsNothing) {
    // The whole name, case and all: no prefixes, no folding, no trimming.
    for (const char* name : {"", "blue", "Red", "RED", "re", "redd", " red", "red ", "light_blue"})
        EXPECT_EQ(fpp::value_of(kColourNames, name), std::nullopt) << "'" << name << "'";
}

TEST(EnumNames, NamesListForMessages) {
    EXPECT_EQ(fpp::names_list(kColourNames), "red, green, light-blue");
    EXPECT_EQ(fpp::names_list(kColourNames, " or "), "red, green or light-blue");
    EXPECT_EQ(fpp::names_list(kSingleNames), "only");
    EXPECT_EQ(fpp::names_list(kSingleNames, " or "), "only");
    EXPECT_EQ(fpp::names_list(fpp::kAxisNames, " or "), "x or y");
}

// Every value of `values` has a name in `table` that reads back to it; the
// table has those values and no others, each once, and no name twice.
template <class Enum, std::size_t N>
void expect_round_trip(const fpp::EnumName<Enum> (&table)[N], const std::vector<Enum>& values) {
    EXPECT_EQ(N, values.size()) << "the table names values the test does not know";
    std::set<std::string> names;
    for (const Enum value : values) {
        const std::string name = fpp::name_of(table, value, "");
        EXPECT_FALSE(name.empty()) << "value " << static_cast<long long>(value) << " has no name";
        EXPECT_EQ(fpp::value_of(table, name), value) << name;
        EXPECT_TRUE(names.insert(name).second) << "'" << name << "' names two values";
    }
}

TEST(EnumNames, CoreTablesRoundTrip) {
    using fpp::Axis, fpp::PhaseShifting, fpp::CodeKind, fpp::DigitOrder;
    expect_round_trip(fpp::kAxisNames, {Axis::x, Axis::y});
    expect_round_trip(
        fpp::kPhaseShiftingNames,
        {PhaseShifting::standard, PhaseShifting::two_plus_one, PhaseShifting::modulated});
    expect_round_trip(fpp::kCodeKindNames, {CodeKind::gray, CodeKind::binary});
    expect_round_trip(fpp::kDigitOrderNames, {DigitOrder::msb_first, DigitOrder::lsb_first});
    using fpp::TableModel, fpp::FrameFileFormat, fpp::BitsInUseSource;
    expect_round_trip(fpp::kTableModelNames,
                      {TableModel::polynomial, TableModel::ray, TableModel::rational});
    expect_round_trip(fpp::kFrameFileFormatNames,
                      {FrameFileFormat::png, FrameFileFormat::tiff, FrameFileFormat::bmp});
    expect_round_trip(
        fpp::kBitsInUseSourceNames,
        {BitsInUseSource::container, BitsInUseSource::declared, BitsInUseSource::found});
}

// The core's functions over the tables: the names they always had.
TEST(EnumNames, CoreFunctionsKeepTheirNames) {
    EXPECT_STREQ(fpp::to_string(fpp::Axis::x), "x");
    EXPECT_STREQ(fpp::to_string(fpp::Axis::y), "y");
    EXPECT_STREQ(fpp::to_string(fpp::PhaseShifting::standard), "standard");
    EXPECT_STREQ(fpp::to_string(fpp::PhaseShifting::two_plus_one), "two_plus_one");
    EXPECT_STREQ(fpp::to_string(fpp::PhaseShifting::modulated), "modulated");
    EXPECT_STREQ(fpp::to_string(fpp::FrameFileFormat::png), "PNG");
    EXPECT_STREQ(fpp::to_string(fpp::FrameFileFormat::tiff), "TIFF");
    EXPECT_STREQ(fpp::to_string(fpp::FrameFileFormat::bmp), "BMP");
    EXPECT_STREQ(fpp::to_string(fpp::BitsInUseSource::container), "container");
    EXPECT_STREQ(fpp::to_string(fpp::BitsInUseSource::declared), "declared");
    EXPECT_STREQ(fpp::to_string(fpp::BitsInUseSource::found), "found");
    for (const auto& [model, name] : fpp::kTableModelNames) {
        EXPECT_STREQ(fpp::to_string(model), name);
        EXPECT_EQ(fpp::parse_table_model(name), model);
    }
    EXPECT_STREQ(fpp::to_string(static_cast<fpp::TableModel>(9)), "unknown");
}

TEST(EnumNames, TableModelParseKeepsItsMessage) {
    try {
        fpp::parse_table_model("cubic");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "unknown table model 'cubic' (polynomial, ray or rational)");
    }
}

} // namespace
