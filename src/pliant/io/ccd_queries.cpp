#include "pliant/io/ccd_queries.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <ranges>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/json_text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

namespace {

constexpr std::size_t ROWS_PER_QUERY = 8;
constexpr std::size_t NUM_COORDINATE_FIELDS = 6;
constexpr std::size_t MAX_FIELDS = 7;
constexpr std::array<const char*, MAX_FIELDS> FIELD_NAMES = {
    "x numerator", "x denominator", "y numerator", "y denominator",
    "z numerator", "z denominator", "truth"};

std::string lower(std::string text) {
    for (char& c : text) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return text;
}

bool ends_with(std::string_view text, std::string_view suffix) {
    return text.size() >= suffix.size() && text.substr(text.size() - suffix.size()) == suffix;
}

std::string_view trim(std::string_view text) {
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) {
        text.remove_prefix(1);
    }
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) {
        text.remove_suffix(1);
    }
    return text;
}

// An optional '-' then at least one decimal digit, nothing else.
bool is_integer_token(std::string_view token) {
    if (!token.empty() && token.front() == '-') {
        token.remove_prefix(1);
    }
    return !token.empty() &&
           std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Parses and checks one line's fields. Throws through `fail` (which adds path, line, column).
class RowParser {
public:
    RowParser(const std::filesystem::path& path, std::size_t line_number)
        : m_path(path), m_line_number(line_number) {}

    [[noreturn]] void fail(std::size_t column, std::string_view message) const {
        throw IoError(fmt::format("{}: line {}: column {} ({}): {}", m_path.string(), m_line_number,
                                  column + 1, FIELD_NAMES[column], message));
    }

    // The field's integer, correctly rounded to double as std::stod would (from_chars is exact
    // for decimal input; integers beyond 2^53, or 2^64, round like any decimal).
    double integer(std::string_view token, std::size_t column) const {
        if (!is_integer_token(token)) {
            fail(column, fmt::format("expected an integer (an optional '-' and digits), got {}",
                                     detail::quote(token)));
        }
        double value = 0.0;
        const char* end = token.data() + token.size();
        const std::from_chars_result result = std::from_chars(token.data(), end, value);
        if (result.ec != std::errc{} || result.ptr != end || !std::isfinite(value)) {
            fail(column, fmt::format("expected an integer of magnitude below 1.8e308 (a finite "
                                     "double), got {} ({} digits)",
                                     detail::quote(token), token.size()));
        }
        return value;
    }

private:
    const std::filesystem::path& m_path;
    std::size_t m_line_number;
};

// The parse of the whole text. Invariant: `queries` holds the complete queries read so far and
// `current` the first `num_rows % 8` rows of the next one.
CcdQuerySet parse_ccd_queries(std::string_view text, const std::filesystem::path& path,
                              CcdQueryKind kind) {
    CcdQuerySet set{.name = path.string(), .kind = kind, .queries = {}};
    const auto fail_line = [&](std::size_t line_number, std::string_view message) {
        throw IoError(fmt::format("{}: line {}: {}", path.string(), line_number, message));
    };

    std::size_t num_fields = 0;        // of every row, fixed by the first row (6 or 7)
    std::size_t first_row_line = 0;    // the line of the file's first row
    std::size_t query_first_line = 0;  // the line of the current query's first row
    std::size_t num_rows = 0;
    std::size_t line_number = 0;
    CcdQuery current;
    std::array<std::string_view, MAX_FIELDS> fields;

    std::size_t pos = 0;
    while (pos < text.size()) {
        // Step 1: the next line, without its \n or \r\n.
        std::size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) {
            end = text.size();
        }
        std::string_view line = text.substr(pos, end - pos);
        pos = end + 1;
        ++line_number;
        if (!line.empty() && line.back() == '\r') {
            line.remove_suffix(1);
        }
        if (trim(line).empty()) {
            continue;
        }

        // Step 2: split on commas; the count is checked before anything is parsed.
        const std::size_t count =
            static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
        if (num_fields == 0) {
            if (count != NUM_COORDINATE_FIELDS && count != MAX_FIELDS) {
                fail_line(line_number,
                          fmt::format("{} fields, expected 6 (x, y, z as numerator,denominator) "
                                      "or 7 (and a 0/1 truth)",
                                      count));
            }
            num_fields = count;
            first_row_line = line_number;
        } else if (count != num_fields) {
            fail_line(line_number,
                      fmt::format("{} fields, expected {} like the first row (line {})", count,
                                  num_fields, first_row_line));
        }
        std::size_t start = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const std::size_t comma = i + 1 < count ? line.find(',', start) : line.size();
            fields[i] = trim(line.substr(start, comma - start));
            start = comma + 1;
        }

        // Step 3: the coordinates, then the truth against the query's first row.
        const RowParser row(path, line_number);
        const std::size_t row_in_query = num_rows % ROWS_PER_QUERY;
        if (row_in_query == 0) {
            query_first_line = line_number;
        }
        Vec3d& point = current.points[row_in_query];
        for (int axis = 0; axis < 3; ++axis) {
            const std::size_t column = 2 * static_cast<std::size_t>(axis);
            const double numerator = row.integer(fields[column], column);
            const double denominator = row.integer(fields[column + 1], column + 1);
            if (denominator == 0.0) {
                row.fail(column + 1, fmt::format("expected a non-zero denominator, got {}",
                                                 detail::quote(fields[column + 1])));
            }
            point[axis] = numerator / denominator;
            if (!std::isfinite(point[axis])) {  // unreachable for |den| >= 1, kept as the contract
                row.fail(column, fmt::format("expected a finite coordinate, got {}", point[axis]));
            }
        }
        std::int8_t truth = -1;
        if (num_fields == MAX_FIELDS) {
            const double value = row.integer(fields[6], 6);
            if (value != 0.0 && value != 1.0) {
                row.fail(6, fmt::format("expected 0 or 1, got {}", detail::quote(fields[6])));
            }
            truth = static_cast<std::int8_t>(value);
        }
        if (row_in_query == 0) {
            current.truth = truth;
        } else if (truth != current.truth) {
            fail_line(line_number,
                      fmt::format("truth differs within a query, expected {} like the query's "
                                  "first row (line {}), got {}",
                                  int{current.truth}, query_first_line, int{truth}));
        }
        ++num_rows;
        if (row_in_query + 1 == ROWS_PER_QUERY) {
            set.queries.push_back(current);
        }
    }

    if (num_rows % ROWS_PER_QUERY != 0) {
        throw IoError(
            fmt::format("{}: {} rows, expected a multiple of 8 (8 rows per query; the "
                        "last query, from line {}, has {} rows)",
                        path.string(), num_rows, query_first_line, num_rows % ROWS_PER_QUERY));
    }
    return set;
}

}  // namespace

std::string_view to_string(CcdQueryKind kind) {
    return kind == CcdQueryKind::edge_edge ? "edge-edge" : "vertex-face";
}

CcdQueryKind ccd_query_kind_from_path(const std::filesystem::path& path) {
    std::error_code ec;
    std::filesystem::path full = std::filesystem::absolute(path, ec);
    if (ec) {
        full = path;
    }
    full = full.lexically_normal();

    // Step 1: the innermost component naming a kind (components innermost first).
    std::vector<std::string> components;
    for (const std::filesystem::path& component : full) {
        components.push_back(lower(component.string()));
    }
    std::reverse(components.begin(), components.end());
    for (const std::string& component : components) {
        const bool is_ee = component.find("edge-edge") != std::string::npos;
        const bool is_vf = component.find("vertex-face") != std::string::npos;
        if (is_ee && is_vf) {
            throw IoError(
                fmt::format("{}: cannot tell the CCD query kind, expected one of "
                            "'edge-edge' or 'vertex-face' in a path component, got "
                            "both in '{}'",
                            path.string(), component));
        }
        if (is_ee || is_vf) {
            return is_ee ? CcdQueryKind::edge_edge : CcdQueryKind::vertex_face;
        }
    }

    // Step 2: the cloth-funnel naming, <frame>ee.csv / <frame>vf.csv.
    const std::string name = lower(full.filename().string());
    if (ends_with(name, "ee.csv")) {
        return CcdQueryKind::edge_edge;
    }
    if (ends_with(name, "vf.csv")) {
        return CcdQueryKind::vertex_face;
    }
    throw IoError(
        fmt::format("{}: cannot tell the CCD query kind, expected 'edge-edge' or "
                    "'vertex-face' in a path component, or a file name ending in "
                    "'ee.csv' or 'vf.csv', got none",
                    path.string()));
}

CcdQuerySet read_ccd_queries(const std::filesystem::path& csv) {
    return read_ccd_queries(csv, ccd_query_kind_from_path(csv));
}

CcdQuerySet read_ccd_queries(const std::filesystem::path& csv, CcdQueryKind kind) {
    const std::string text = read_file(csv);
    return parse_ccd_queries(text, csv, kind);
}

std::vector<bool> read_mathematica_bools(const std::filesystem::path& json) {
    const std::string text = read_file(json);
    const nlohmann::json value = parse_json(text, json.string());
    if (!value.is_array()) {
        throw IoError(fmt::format("{}: expected a JSON array of booleans, got a {}", json.string(),
                                  value.type_name()));
    }
    std::vector<bool> bools;
    bools.reserve(value.size());
    for (std::size_t i = 0; i < value.size(); ++i) {
        const nlohmann::json& element = value[i];
        if (!element.is_boolean()) {
            throw IoError(fmt::format("{}: element {} (0-based), expected true or false, got {}",
                                      json.string(), i, detail::quote(element.dump())));
        }
        bools.push_back(element.get<bool>());
    }
    return bools;
}

std::vector<std::filesystem::path> find_ccd_query_files(const std::filesystem::path& path) {
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) {
        throw IoError(
            fmt::format("{}: cannot find CCD queries, expected a file or a directory, "
                        "got {}",
                        path.string(), ec ? ec.message() : "no such path"));
    }
    if (std::filesystem::is_regular_file(status)) {
        return {path};
    }
    if (!std::filesystem::is_directory(status)) {
        throw IoError(
            fmt::format("{}: cannot read CCD queries, expected a file or a directory, "
                        "got a special file",
                        path.string()));
    }

    std::vector<std::filesystem::path> files;
    std::filesystem::recursive_directory_iterator it(path, ec);
    const std::filesystem::recursive_directory_iterator end;
    for (; !ec && it != end; it.increment(ec)) {
        const std::filesystem::directory_entry& entry = *it;
        std::error_code entry_ec;
        if (entry.is_regular_file(entry_ec) && lower(entry.path().extension().string()) == ".csv") {
            files.push_back(entry.path());
        }
    }
    if (ec) {
        throw IoError(
            fmt::format("{}: cannot list the directory: {}", path.string(), ec.message()));
    }
    std::sort(files.begin(), files.end());
    return files;
}

}  // namespace pliant::io
