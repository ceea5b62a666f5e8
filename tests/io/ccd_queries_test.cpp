#include "pliant/io/ccd_queries.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::TempDir;
using test::write_bytes;

namespace fs = std::filesystem;

// 2^65: a denominator no 64-bit integer holds.
constexpr const char* TWO_TO_65 = "36893488147419103232";

// Writes `text` to dir/relative (creating folders) and returns the path.
fs::path write_file(const TempDir& dir, const std::string& relative, std::string_view text) {
    fs::path path = dir / relative;
    fs::create_directories(path.parent_path());
    write_bytes(path, text);
    return path;
}

// `num_queries` queries of 8 rows, row r of query q at (q + r/8, -r, 1/4), with a truth column
// (`truth` 0 or 1) or without (`truth` -1).
std::string simple_rows(int num_queries, int truth) {
    std::string text;
    for (int q = 0; q < num_queries; ++q) {
        for (int r = 0; r < 8; ++r) {
            // Appended piece by piece: g++ 12 warns falsely (-Wrestrict) on "," + std::string.
            text += std::to_string(8 * q + r);
            text += ",8,";
            text += std::to_string(-r);
            text += ",1,1,4";
            if (truth >= 0) {
                text += ',';
                text += std::to_string(truth);
            }
            text += '\n';
        }
    }
    return text;
}

void expect_same_bits(double actual, double expected, const std::string& what) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(actual), std::bit_cast<std::uint64_t>(expected))
        << what << ": got " << actual << ", expected " << expected;
}

// Expects read_ccd_queries on `text` (in a vertex-face folder) to throw IoError whose message
// starts with the path and contains every fragment.
void expect_broken(std::string_view text, std::initializer_list<std::string_view> fragments) {
    TempDir dir;
    const fs::path path = write_file(dir, "vertex-face/broken.csv", text);
    const std::string message = expect_io_error([&] { read_ccd_queries(path); }, fragments);
    EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
}

// ---------------------------------------------------------------------------------------------
// Reading valid files

TEST(CcdQueries, ReadsVertexFaceWithExactValues) {
    TempDir dir;
    // Rows: plain fractions, negative numerators, a 2^65 denominator, a numerator beyond 2^64
    // that rounds to 2^65 as a double (so the quotient is exactly 1), zero and -0 numerators.
    const std::string text = std::string("1,2,-3,4,5,") + TWO_TO_65 + ",1\n" +
                             "-7,1,0,1,36893488147419103233," + TWO_TO_65 + ",1\n" +
                             "0,1,-0,1,3,1,1\n" + "-1,3,2,3,1,-2,1\n" +
                             "9007199254740993,1,1,1024,-1,1024,1\n" + "0,1,0,1,0,1,1\n" +
                             "1,1,1,1,1,1,1\n" + "-1,1,-1,1,-1,1,1\n";
    const fs::path path = write_file(dir, "set/vertex-face/data_0_0.csv", text);
    const CcdQuerySet set = read_ccd_queries(path);

    EXPECT_EQ(set.name, path.string());
    EXPECT_EQ(set.kind, CcdQueryKind::vertex_face);
    ASSERT_EQ(set.queries.size(), 1u);
    const CcdQuery& q = set.queries[0];
    EXPECT_EQ(q.truth, 1);

    expect_same_bits(q.points[0].x, 0.5, "row 1 x");
    expect_same_bits(q.points[0].y, -0.75, "row 1 y");
    expect_same_bits(q.points[0].z, std::ldexp(5.0, -65), "row 1 z");
    expect_same_bits(q.points[1].x, -7.0, "row 2 x");
    expect_same_bits(q.points[1].y, 0.0, "row 2 y");
    expect_same_bits(q.points[1].z, 1.0, "row 2 z");
    expect_same_bits(q.points[2].y, -0.0, "row 3 y (-0/1)");
    expect_same_bits(q.points[3].x, -1.0 / 3.0, "row 4 x (rounded like stod/stod)");
    expect_same_bits(q.points[3].z, -0.5, "row 4 z (negative denominator)");
    expect_same_bits(q.points[4].x, 9007199254740992.0, "row 5 x (2^53 + 1 rounds to even)");
    expect_same_bits(q.points[4].y, 1.0 / 1024.0, "row 5 y");
    expect_same_bits(q.points[7].z, -1.0, "row 8 z");

    // Every coordinate is std::stod(num) / std::stod(den), the data README's definition.
    const std::vector<std::vector<std::string>> fields = {
        {"1", "2", "-3", "4", "5", TWO_TO_65},
        {"-7", "1", "0", "1", "36893488147419103233", TWO_TO_65},
        {"0", "1", "-0", "1", "3", "1"},
        {"-1", "3", "2", "3", "1", "-2"},
        {"9007199254740993", "1", "1", "1024", "-1", "1024"},
        {"0", "1", "0", "1", "0", "1"},
        {"1", "1", "1", "1", "1", "1"},
        {"-1", "1", "-1", "1", "-1", "1"}};
    for (int r = 0; r < 8; ++r) {
        for (int axis = 0; axis < 3; ++axis) {
            const std::size_t column = 2 * static_cast<std::size_t>(axis);
            const double expected = std::stod(fields[r][column]) / std::stod(fields[r][column + 1]);
            expect_same_bits(q.points[r][axis], expected,
                             "row " + std::to_string(r + 1) + " axis " + std::to_string(axis));
        }
    }
}

TEST(CcdQueries, ReadsEdgeEdgeQueriesInFileOrder) {
    TempDir dir;
    const std::string text = simple_rows(1, 0) + simple_rows(2, 1).substr(simple_rows(1, 1).size());
    const fs::path path = write_file(dir, "edge-edge/data.csv", text);
    const CcdQuerySet set = read_ccd_queries(path);
    EXPECT_EQ(set.kind, CcdQueryKind::edge_edge);
    ASSERT_EQ(set.queries.size(), 2u);
    EXPECT_EQ(set.queries[0].truth, 0);
    EXPECT_EQ(set.queries[1].truth, 1);
    for (int q = 0; q < 2; ++q) {
        for (int r = 0; r < 8; ++r) {
            const Vec3d expected{(8.0 * q + r) / 8.0, -static_cast<double>(r), 0.25};
            EXPECT_EQ(set.queries[q].points[r], expected) << "query " << q << " row " << r;
        }
    }
}

TEST(CcdQueries, SixColumnsGiveUnknownTruth) {
    TempDir dir;
    const fs::path path = write_file(dir, "queries/227ee.csv", simple_rows(3, -1));
    const CcdQuerySet set = read_ccd_queries(path);
    EXPECT_EQ(set.kind, CcdQueryKind::edge_edge);
    ASSERT_EQ(set.queries.size(), 3u);
    for (const CcdQuery& q : set.queries) {
        EXPECT_EQ(q.truth, -1);
    }
    EXPECT_EQ(set.queries[2].points[7], (Vec3d{23.0 / 8.0, -7.0, 0.25}));
}

TEST(CcdQueries, ToleratesCrLfBlankLinesSpacesAndNoFinalNewline) {
    TempDir dir;
    std::string text = "\r\n";
    for (int r = 0; r < 8; ++r) {
        text += " 1 ,\t2,3,4,5,6 , 0 \r\n\n";
    }
    text.resize(text.size() - 3);  // the last row ends without a newline
    const fs::path path = write_file(dir, "vertex-face/crlf.csv", text);
    const CcdQuerySet set = read_ccd_queries(path);
    ASSERT_EQ(set.queries.size(), 1u);
    EXPECT_EQ(set.queries[0].truth, 0);
    EXPECT_EQ(set.queries[0].points[7], (Vec3d{0.5, 0.75, 5.0 / 6.0}));
}

TEST(CcdQueries, EmptyFileGivesNoQueries) {
    TempDir dir;
    for (const std::string_view text : {"", "\n", "\r\n\r\n  \n"}) {
        const fs::path path = write_file(dir, "empty-vf.csv", text);
        const CcdQuerySet set = read_ccd_queries(path);
        EXPECT_EQ(set.kind, CcdQueryKind::vertex_face);
        EXPECT_TRUE(set.queries.empty());
    }
}

TEST(CcdQueries, ExplicitKindOverridesThePath) {
    TempDir dir;
    const fs::path path = write_file(dir, "vertex-face/q.csv", simple_rows(1, 1));
    EXPECT_EQ(read_ccd_queries(path, CcdQueryKind::edge_edge).kind, CcdQueryKind::edge_edge);
    const fs::path anonymous = write_file(dir, "q.csv", simple_rows(1, 1));
    EXPECT_EQ(read_ccd_queries(anonymous, CcdQueryKind::vertex_face).queries.size(), 1u);
}

// ---------------------------------------------------------------------------------------------
// Kind from path

TEST(CcdQueries, KindFromPath) {
    EXPECT_EQ(ccd_query_kind_from_path("/d/unit-tests/edge-edge/data_0_0.csv"),
              CcdQueryKind::edge_edge);
    EXPECT_EQ(ccd_query_kind_from_path("/d/unit-tests/vertex-face/data_0_0.csv"),
              CcdQueryKind::vertex_face);
    EXPECT_EQ(ccd_query_kind_from_path("rel/Edge-Edge/x.csv"), CcdQueryKind::edge_edge);
    EXPECT_EQ(ccd_query_kind_from_path("my-vertex-face-set.csv"), CcdQueryKind::vertex_face);
    EXPECT_EQ(ccd_query_kind_from_path("/d/cloth-funnel/queries/227ee.csv"),
              CcdQueryKind::edge_edge);
    EXPECT_EQ(ccd_query_kind_from_path("/d/cloth-funnel/queries/227vf.csv"),
              CcdQueryKind::vertex_face);
    EXPECT_EQ(ccd_query_kind_from_path("227VF.CSV"), CcdQueryKind::vertex_face);
    // The innermost named component wins; a named component beats the file-name suffix.
    EXPECT_EQ(ccd_query_kind_from_path("/vertex-face-runs/edge-edge/x.csv"),
              CcdQueryKind::edge_edge);
    EXPECT_EQ(ccd_query_kind_from_path("/d/vertex-face/coffee.csv"), CcdQueryKind::vertex_face);
    // The path is normalised before looking: "edge-edge/.." is not a component of the file.
    EXPECT_EQ(ccd_query_kind_from_path("/d/vertex-face/edge-edge/../x.csv"),
              CcdQueryKind::vertex_face);

    expect_io_error([] { ccd_query_kind_from_path("/d/unit-tests/data_0_0.csv"); },
                    {"/d/unit-tests/data_0_0.csv: ", "cannot tell the CCD query kind",
                     "'edge-edge'", "'vertex-face'", "'ee.csv'", "'vf.csv'"});
    expect_io_error([] { ccd_query_kind_from_path("/d/ee.csv.bak"); }, {"cannot tell"});
    expect_io_error([] { ccd_query_kind_from_path("/d/edge-edge-vs-vertex-face/x.csv"); },
                    {"got both", "edge-edge-vs-vertex-face"});
    TempDir dir;
    const fs::path path = write_file(dir, "data_0_0.csv", simple_rows(1, 1));
    expect_io_error([&] { read_ccd_queries(path); }, {path.string(), "cannot tell"});
}

// ---------------------------------------------------------------------------------------------
// Malformed files

TEST(CcdQueries, RowsNotAMultipleOfEight) {
    const std::string seven = simple_rows(1, 1).substr(0, simple_rows(1, 1).rfind("7,8"));
    expect_broken(seven, {"7 rows", "expected a multiple of 8"});
    expect_broken(simple_rows(1, 0) + "1,1,1,1,1,1,0\n", {"9 rows", "from line 9"});
}

TEST(CcdQueries, WrongFieldCount) {
    expect_broken("1,1,1,1,1\n", {"line 1: 5 fields", "expected 6", "or 7"});
    expect_broken("1,1,1,1,1,1,1,1\n", {"line 1: 8 fields"});
    expect_broken("\n1,1,1,1,1,1,1\n1,1,1,1,1\n",
                  {"line 3: 5 fields", "expected 7", "first row (line 2)"});
    expect_broken("1,1,1,1,1,1,1\n1,1,1,1,1,1\n", {"line 2: 6 fields, expected 7"});
    expect_broken("1,1,1,1,1,1\n1,1,1,1,1,1,1\n", {"line 2: 7 fields, expected 6"});
    expect_broken("1,1,1,1,1,1,,\n", {"line 1: 8 fields"});
}

TEST(CcdQueries, NonIntegerTokens) {
    const std::string ok_row = "1,1,1,1,1,1,1\n";
    for (const std::string_view bad :
         {"1.5", "1e3", "+1", "--1", "-", "", "0x10", "abc", "1 2", "inf", "nan", "\xff"}) {
        const std::string text = ok_row + "1,1,1," + std::string(bad) + ",1,1,1\n";
        expect_broken(text, {"line 2: column 4 (y denominator): expected an integer"});
    }
    expect_broken("1,1,1,1,1,1,x\n", {"line 1: column 7 (truth): expected an integer", "'x'"});
    expect_broken("1.25,1,1,1,1,1,1\n", {"line 1: column 1 (x numerator)", "got '1.25'"});
}

TEST(CcdQueries, IntegerBeyondDoubleRange) {
    const std::string huge = "1" + std::string(400, '0');
    expect_broken("1,1,1,1," + huge + ",1,1\n", {"line 1: column 5 (z numerator)", "401 digits"});
    expect_broken("1,-" + huge + ",1,1,1,1,1\n", {"line 1: column 2 (x denominator)"});
}

TEST(CcdQueries, ZeroDenominator) {
    expect_broken(simple_rows(1, 1) + "1,1,1,0,1,1,1\n",
                  {"line 9: column 4 (y denominator): expected a non-zero denominator, got '0'"});
    expect_broken("1,1,1,1,1,-000,1\n", {"line 1: column 6", "got '-000'"});
}

TEST(CcdQueries, TruthOutsideZeroOne) {
    expect_broken("1,1,1,1,1,1,2\n", {"line 1: column 7 (truth): expected 0 or 1, got '2'"});
    expect_broken("1,1,1,1,1,1,-1\n", {"line 1: column 7 (truth)", "got '-1'"});
}

TEST(CcdQueries, TruthDiffersWithinAQuery) {
    // Query 2 spans lines 9-16; its 6th row (line 14) says 1 where its first row says 0.
    std::string text = simple_rows(1, 1);
    for (int r = 0; r < 8; ++r) {
        text += r == 5 ? "1,1,1,1,1,1,1\n" : "1,1,1,1,1,1,0\n";
    }
    expect_broken(text, {"line 14: truth differs within a query",
                         "expected 0 like the query's first row (line 9), got 1"});
}

TEST(CcdQueries, GarbageDoesNotCrash) {
    std::string garbage;
    std::uint32_t state = 12345;
    for (int i = 0; i < 1 << 16; ++i) {
        state = state * 1664525u + 1013904223u;
        garbage.push_back(static_cast<char>(state >> 24));
    }
    TempDir dir;
    const fs::path path = write_file(dir, "vertex-face/garbage.csv", garbage);
    expect_io_error([&] { read_ccd_queries(path); }, {path.string() + ": line "});
    // One huge line of commas stops at the field count.
    expect_broken(std::string(1 << 20, ','), {"line 1: 1048577 fields"});
    expect_io_error([&] { read_ccd_queries(dir / "vertex-face/missing.csv"); },
                    {"missing.csv", "cannot open"});
}

// ---------------------------------------------------------------------------------------------
// Mathematica booleans

TEST(CcdQueries, ReadsMathematicaBools) {
    TempDir dir;
    const fs::path path = write_file(dir, "b.json", "[true,false, true ,false]\n");
    EXPECT_EQ(read_mathematica_bools(path), (std::vector<bool>{true, false, true, false}));
    EXPECT_TRUE(read_mathematica_bools(write_file(dir, "e.json", "[]")).empty());

    const fs::path not_array = write_file(dir, "o.json", "{\"a\": true}");
    expect_io_error([&] { read_mathematica_bools(not_array); },
                    {not_array.string() + ": ", "expected a JSON array", "object"});
    const fs::path bad_element = write_file(dir, "n.json", "[true, 1, false]");
    expect_io_error([&] { read_mathematica_bools(bad_element); },
                    {"element 1", "expected true or false", "got '1'"});
    const fs::path bad_json = write_file(dir, "j.json", "[true, fals");
    expect_io_error([&] { read_mathematica_bools(bad_json); },
                    {bad_json.string() + ": not valid JSON"});
    const fs::path overflow = write_file(dir, "h.json", "[true, 1e999]");
    expect_io_error([&] { read_mathematica_bools(overflow); },
                    {overflow.string() + ": not valid JSON", "number overflow"});
}

// ---------------------------------------------------------------------------------------------
// Finding files

TEST(CcdQueries, FindsCsvFilesBelowAFolderSorted) {
    TempDir dir;
    write_file(dir, "b/edge-edge/data_0_1.csv", "");
    write_file(dir, "b/edge-edge/data_0_0.csv", "");
    write_file(dir, "a/vertex-face/data_0_0.CSV", "");
    write_file(dir, "a/vertex-face/notes.txt", "");
    write_file(dir, "a/README.md", "");
    fs::create_directories(dir / "empty/edge-edge");

    const std::vector<fs::path> files = find_ccd_query_files(dir.path());
    const std::vector<fs::path> expected = {dir / "a/vertex-face/data_0_0.CSV",
                                            dir / "b/edge-edge/data_0_0.csv",
                                            dir / "b/edge-edge/data_0_1.csv"};
    EXPECT_EQ(files, expected);

    const fs::path single = dir / "a/vertex-face/notes.txt";
    EXPECT_EQ(find_ccd_query_files(single), std::vector<fs::path>{single});
    EXPECT_TRUE(find_ccd_query_files(dir / "empty").empty());
    expect_io_error([&] { find_ccd_query_files(dir / "nowhere"); },
                    {"nowhere: cannot find CCD queries"});
}

// ---------------------------------------------------------------------------------------------
// The shared benchmark data (skipped when absent)

const fs::path SHARED_DATA = fs::path(PLIANT_SHARED_DATA_DIR);

struct Totals {
    std::size_t num_files = 0;
    std::size_t num_queries = 0;
    std::size_t num_positives = 0;
    std::size_t num_vf = 0;
    std::size_t num_ee = 0;
};

Totals read_all(const fs::path& folder) {
    Totals totals;
    for (const fs::path& file : find_ccd_query_files(folder)) {
        const CcdQuerySet set = read_ccd_queries(file);
        ++totals.num_files;
        totals.num_queries += set.queries.size();
        (set.kind == CcdQueryKind::vertex_face ? totals.num_vf : totals.num_ee) +=
            set.queries.size();
        for (const CcdQuery& q : set.queries) {
            EXPECT_NE(q.truth, -1) << file;
            totals.num_positives += q.truth == 1 ? 1 : 0;
            for (const Vec3d& p : q.points) {
                EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
            }
        }
    }
    return totals;
}

TEST(CcdQueries, SampleQueriesCounts) {
    const fs::path root = SHARED_DATA / "ccd-queries";
    if (!fs::is_directory(root)) {
        GTEST_SKIP() << root << " is absent (shared benchmark data, not part of a clone)";
    }
    const Totals unit = read_all(root / "unit-tests");
    EXPECT_EQ(unit.num_queries, 324u);
    EXPECT_EQ(unit.num_positives, 160u);

    Totals erleben;
    std::size_t num_erleben_sets = 0;
    for (const auto& entry : fs::directory_iterator(root)) {
        if (entry.path().filename().string().rfind("erleben-", 0) == 0) {
            const Totals t = read_all(entry.path());
            ++num_erleben_sets;
            erleben.num_queries += t.num_queries;
            erleben.num_positives += t.num_positives;
        }
    }
    EXPECT_EQ(num_erleben_sets, 5u);
    EXPECT_EQ(erleben.num_queries, 2500u);
    EXPECT_EQ(erleben.num_positives, 127u);

    const Totals all = read_all(root);
    EXPECT_EQ(all.num_files, 24u);
    EXPECT_EQ(all.num_queries, 324u + 2500u);
    std::cout << "ccd-queries: unit-tests " << unit.num_queries << " queries ("
              << unit.num_positives << " positive, " << unit.num_vf << " vf, " << unit.num_ee
              << " ee); erleben-* " << erleben.num_queries << " (" << erleben.num_positives
              << " positive)\n";
}

TEST(CcdQueries, ClothFunnelQueriesMatchTheirBooleans) {
    const fs::path root = SHARED_DATA / "cloth-funnel";
    if (!fs::is_directory(root / "queries")) {
        GTEST_SKIP() << root / "queries"
                     << " is absent (shared benchmark data)";
    }
    for (const std::string kind : {"vf", "ee"}) {
        const CcdQuerySet set = read_ccd_queries(root / "queries" / ("227" + kind + ".csv"));
        EXPECT_EQ(set.kind, kind == "vf" ? CcdQueryKind::vertex_face : CcdQueryKind::edge_edge);
        EXPECT_FALSE(set.queries.empty());
        for (const CcdQuery& q : set.queries) {
            ASSERT_EQ(q.truth, -1);  // 6 columns
        }
        const std::vector<bool> truth =
            read_mathematica_bools(root / "mma_bool" / ("227" + kind + "_mma_bool.json"));
        EXPECT_EQ(truth.size(), set.queries.size()) << kind;
        std::size_t num_positives = 0;
        for (const bool b : truth) {
            num_positives += b ? 1 : 0;
        }
        std::cout << "cloth-funnel 227" << kind << ": " << set.queries.size() << " queries, "
                  << num_positives << " positive\n";
    }
}

}  // namespace
}  // namespace pliant::io
