// Continuous collision detection queries in the Sample-Queries CSV format of Wang, Ferguson,
// Schneider, Jiang, Attene, Panozzo, "A Large-scale Benchmark and an Inclusion-based Algorithm for
// Continuous Collision Detection", ACM TOG 40(5), 2021 (github.com/Continuous-Collision-Detection/
// Sample-Queries, FORMAT.md), and the cloth-funnel queries of Sample-Scalable-CCD-Data.
//
// File format: 8 rows per query, one vertex position per row, comma-separated integer fields
//   x_num, x_den, y_num, y_den, z_num, z_den [, truth]
// Each coordinate is the rational num/den, read as std::stod(num) / std::stod(den): both integers
// are rounded to double (denominators are powers of two, some beyond 2^64), then divided. For the
// benchmark data this is exact. The optional 7th column is the ground truth, 0 or 1, the same on
// the 8 rows of a query. Row order within a query:
//   vertex-face: v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1
//   edge-edge:   ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1
// The kind is not in the file: it comes from the path (ccd_query_kind_from_path).
//
// Thread safety: every function is reentrant; nothing is shared between calls.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::io {

enum class CcdQueryKind { vertex_face, edge_edge };

// "vertex-face" or "edge-edge".
std::string_view to_string(CcdQueryKind kind);

// One query: the 8 rows of the file in file order (see the row order above), and the ground truth
// (1 colliding, 0 not colliding, -1 unknown: the file has no truth column).
struct CcdQuery {
    std::array<Vec3d, 8> points;
    std::int8_t truth = -1;
};

// The queries of one file. `name` is the path as given to read_ccd_queries (path.string()).
struct CcdQuerySet {
    std::string name;
    CcdQueryKind kind = CcdQueryKind::vertex_face;
    std::vector<CcdQuery> queries;
};

// The kind of the queries in a file, from its path (compared in lower case, on the absolute,
// lexically normalised path; the file need not exist):
//   1. the innermost path component that contains "edge-edge" or "vertex-face" (the Sample-Queries
//      layout <set>/edge-edge/data_0_0.csv) decides;
//   2. otherwise a file name ending in "ee.csv" or "vf.csv" (cloth-funnel queries/227ee.csv).
// Throws IoError "<path>: cannot tell the CCD query kind, expected …, got …" naming the accepted
// patterns when none matches, or when the deciding component contains both names.
CcdQueryKind ccd_query_kind_from_path(const std::filesystem::path& path);

// Reads a query file; the kind is ccd_query_kind_from_path(csv) (throws as that does) or given.
// Rules: lines end at \n or \r\n; empty lines are skipped (line numbers still count them); spaces
// and tabs around a field are ignored; a field is an integer: an optional '-' then decimal digits
// (no '+', no exponent, no point), of any length. Every row of a file has the same number of
// fields, 6 (no truth: every query gets truth -1) or 7. An empty file (or only empty lines) gives a
// set with no queries.
// Throws IoError "<path>: [line N: ][column C: ]<what>, expected <x>, got <y>" for: a missing or
// unreadable file; a row with other than 6 or 7 fields, or with a different count from the first
// row; a field that is not an integer, or whose magnitude overflows a double (> ~1.8e308); a zero
// denominator; a non-finite coordinate; a truth other than 0 or 1, or differing within a query
// (naming the line of the first row that differs); a number of rows that is not a multiple of 8.
// Cost: one bulk read of the file, then one O(file size) pass; peak memory is the file plus the
// queries (200 bytes each).
CcdQuerySet read_ccd_queries(const std::filesystem::path& csv);
CcdQuerySet read_ccd_queries(const std::filesystem::path& csv, CcdQueryKind kind);

// The ground truth of the cloth-funnel queries (mma_bool/227vf_mma_bool.json): a JSON array of
// booleans, one per query of the matching CSV file, in query order.
// Throws IoError "<path>: …" for a missing or unreadable file, text that is not JSON, a top-level
// value that is not an array, and an element that is not true or false (naming its index).
std::vector<bool> read_mathematica_bools(const std::filesystem::path& json);

// The query files to read for a command-line PATH: a file (of any name) gives itself; a directory
// gives every regular file below it (recursively, not following directory symlinks) whose
// extension is ".csv" (any case), sorted by path. A directory without such files gives an empty
// list. Throws IoError "<path>: …" when the path does not exist, is neither a file nor a
// directory, or the directory cannot be listed.
std::vector<std::filesystem::path> find_ccd_query_files(const std::filesystem::path& path);

}  // namespace pliant::io
