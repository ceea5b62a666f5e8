// `pliant ccd` end to end: query files in the Sample-Queries format, false negatives against the
// ground truth (must be 0 on every shared set; the external tests skip when ../shared/data is
// absent), and clear errors for broken files.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "integration/run_cli.hpp"

namespace pliant::test {
namespace {

const std::filesystem::path SHARED(PLIANT_SHARED_DATA_DIR);

void write_text(const std::filesystem::path& path, const std::string& text) {
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path) << text;
}

// A vertex falling through the middle of a triangle (colliding), as 8 rational rows with truth.
std::string falling_vertex_query(int truth) {
    std::string rows;
    const char* points[8] = {"1 4 1 4 1 1",  "0 1 0 1 0 1", "1 1 0 1 0 1", "0 1 1 1 0 1",
                             "1 4 1 4 -1 1", "0 1 0 1 0 1", "1 1 0 1 0 1", "0 1 1 1 0 1"};
    for (const char* p : points) {
        std::string row = p;
        for (char& c : row) {
            c = c == ' ' ? ',' : c;
        }
        rows += row + "," + std::to_string(truth) + "\n";
    }
    return rows;
}

TEST(CcdCommand, ReportsFalseNegativesAndPositivesPerFile) {
    ScratchDir scratch;
    write_text(scratch / "vertex-face" / "a.csv",
               falling_vertex_query(1) + falling_vertex_query(0));
    const CliResult r = run_cli("ccd " + quoted(scratch.path()) + " --json", scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json json = nlohmann::json::parse(r.out);
    ASSERT_EQ(json.at("sets").size(), 1u);
    const nlohmann::json& set = json.at("sets")[0];
    EXPECT_EQ(set.at("kind"), "vertex-face");
    EXPECT_EQ(set.at("queries"), 2);
    EXPECT_EQ(set.at("hits"), 2);
    EXPECT_EQ(set.at("positives"), 1);
    EXPECT_EQ(set.at("false_negatives"), 0);
    EXPECT_EQ(set.at("false_positives"), 1);  // the second copy is labelled 0 on purpose
    EXPECT_EQ(json.at("false_negatives"), 0);
}

TEST(CcdCommand, BrokenFileNamesFileAndLine) {
    ScratchDir scratch;
    std::string text = falling_vertex_query(1);
    text.replace(text.find("1,4,1,4,1,1"), 11, "1,4,1,x,1,1");
    write_text(scratch / "vertex-face" / "bad.csv", text);
    const CliResult r = run_cli("ccd " + quoted(scratch / "vertex-face" / "bad.csv"), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("bad.csv"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("line 1"), std::string::npos) << r.err;
    const CliResult missing = run_cli("ccd " + quoted(scratch / "nothing-here"), scratch);
    EXPECT_EQ(missing.exit_code, 1);
    const CliResult negative =
        run_cli("ccd " + quoted(scratch.path()) + " --min-separation -1", scratch);
    EXPECT_EQ(negative.exit_code, 2);
    const CliResult not_a_number =
        run_cli("ccd " + quoted(scratch.path()) + " --min-separation nan", scratch);
    EXPECT_EQ(not_a_number.exit_code, 2);
    EXPECT_NE(not_a_number.err.find("finite"), std::string::npos) << not_a_number.err;
}

TEST(CcdCommandExternal, NoFalseNegativesOnSampleQueriesAndClothFunnel) {
    const std::filesystem::path queries = SHARED / "ccd-queries";
    const std::filesystem::path funnel = SHARED / "cloth-funnel" / "queries";
    if (!std::filesystem::exists(queries) || !std::filesystem::exists(funnel)) {
        GTEST_SKIP() << "external data not found under " << SHARED.string();
    }
    ScratchDir scratch;
    for (const std::filesystem::path& path : {queries, funnel}) {
        const CliResult r = run_cli("ccd " + quoted(path) + " --json", scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const nlohmann::json json = nlohmann::json::parse(r.out);
        EXPECT_EQ(json.at("false_negatives"), 0) << path.string();
        std::int64_t queries_total = 0;
        for (const nlohmann::json& set : json.at("sets")) {
            ASSERT_FALSE(set.at("positives").is_null()) << set.at("name");  // ground truth found
            queries_total += set.at("queries").get<std::int64_t>();
        }
        EXPECT_EQ(queries_total, path == queries ? 2824 : 355) << path.string();
    }
}

}  // namespace
}  // namespace pliant::test
