// Helpers for the file-format tests (io, pipeline readers): a scratch directory under the system
// temp directory that is removed with everything in it, byte-exact file writing and reading, a
// check that a call throws IoError whose message contains given fragments, and meshes with awkward
// numbers for round trips.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::io::test {

// temp_directory_path()/"pliant-test-<pid>-<counter>-<test name>", created empty.
class TempDir {
public:
    TempDir() {
        static std::atomic<int> counter{0};
        const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = "pliant-test-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter.fetch_add(1));
        if (info != nullptr) {
            name += std::string("-") + info->name();
        }
        for (char& c : name) {
            if (c == '/') {
                c = '_';
            }
        }
        m_path = std::filesystem::temp_directory_path() / name;
        std::filesystem::remove_all(m_path);
        std::filesystem::create_directories(m_path);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    ~TempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(m_path, ignored);
    }

    const std::filesystem::path& path() const { return m_path; }
    std::filesystem::path operator/(std::string_view name) const { return m_path / name; }

    // The names of the directory's entries, sorted.
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& entry : std::filesystem::directory_iterator(m_path)) {
            names.push_back(entry.path().filename().string());
        }
        std::sort(names.begin(), names.end());
        return names;
    }

private:
    std::filesystem::path m_path;
};

inline void write_bytes(const std::filesystem::path& path, std::string_view bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    ASSERT_TRUE(out.good()) << path;
}

inline std::string read_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes;
    if (in) {
        in.seekg(0, std::ios::end);
        bytes.resize(static_cast<std::size_t>(in.tellg()));
        in.seekg(0, std::ios::beg);
        in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
    return bytes;
}

// Runs `f`, expects pliant::IoError, and checks that its message contains every fragment.
// Returns the message ("" if nothing or something else was thrown).
template <typename F>
std::string expect_io_error(F&& f, std::initializer_list<std::string_view> fragments) {
    std::string message;
    try {
        f();
        ADD_FAILURE() << "expected pliant::IoError, nothing was thrown";
        return {};
    } catch (const IoError& e) {
        message = e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected pliant::IoError, got another exception: " << e.what();
        return {};
    }
    for (const std::string_view fragment : fragments) {
        EXPECT_NE(message.find(fragment), std::string::npos)
            << "message: " << message << "\nmissing: " << fragment;
    }
    return message;
}

// A mesh whose coordinates exercise every corner of the number format: ±0, the smallest
// subnormal, the smallest normal, the largest finite value, values with no short decimal form,
// and random bit patterns over the whole finite range. #V = 3 * 40, #T = #V - 2 plus random
// distinct triples.
template <typename Real>
geometry::BasicTriangleMesh<Real> tricky_mesh(std::uint32_t seed = 7) {
    using Limits = std::numeric_limits<Real>;
    std::vector<Real> values = {Real(0),
                                -Real(0),
                                Real(1),
                                Real(-1),
                                Real(0.1),
                                Real(1) / Real(3),
                                Limits::min(),
                                Limits::denorm_min(),
                                -Limits::denorm_min(),
                                Limits::max(),
                                -Limits::max(),
                                Limits::epsilon(),
                                Real(123456.789),
                                Real(-2.5e-7),
                                Real(1e30)};
    std::mt19937_64 rng(seed);
    while (values.size() < 120) {
        using Bits = std::conditional_t<sizeof(Real) == 4, std::uint32_t, std::uint64_t>;
        const auto value = std::bit_cast<Real>(static_cast<Bits>(rng()));
        if (std::isfinite(value)) {
            values.push_back(value);
        }
    }
    geometry::BasicTriangleMesh<Real> mesh;
    for (std::size_t i = 0; i + 2 < values.size(); i += 3) {
        mesh.positions.push_back({values[i], values[i + 1], values[i + 2]});
    }
    const auto n = static_cast<std::int32_t>(mesh.positions.size());
    for (std::int32_t i = 0; i + 2 < n; ++i) {
        mesh.triangles.push_back({i, i + 1, i + 2});
    }
    std::uniform_int_distribution<std::int32_t> pick(0, n - 1);
    for (int t = 0; t < 20; ++t) {
        const std::int32_t a = pick(rng);
        const std::int32_t b = (a + 1 + pick(rng) % (n - 1)) % n;
        std::int32_t c = pick(rng);
        while (c == a || c == b) {
            c = pick(rng);
        }
        mesh.triangles.push_back({a, b, c});
    }
    return mesh;
}

// Expects `read` to hold exactly the numbers of `written` (bit for bit, after widening float to
// double) and the same triangles.
template <typename Real>
void expect_bitwise_equal(const geometry::BasicTriangleMesh<Real>& written,
                          const geometry::TriangleMeshD& read) {
    ASSERT_EQ(read.num_vertices(), written.num_vertices());
    for (std::size_t v = 0; v < written.num_vertices(); ++v) {
        for (int k = 0; k < 3; ++k) {
            const auto expected = static_cast<double>(written.positions[v][k]);
            ASSERT_EQ(std::bit_cast<std::uint64_t>(read.positions[v][k]),
                      std::bit_cast<std::uint64_t>(expected))
                << "vertex " << v << " axis " << k << ": read " << read.positions[v][k]
                << ", wrote " << expected;
        }
    }
    ASSERT_EQ(read.triangles, written.triangles);
}

// For text written from floats (the shortest decimals that round back to them, or 9 significant
// digits) and read at double precision: the decimals read back are not the floats' exact values,
// but each rounds to the float written.
inline void expect_rounds_to(const geometry::TriangleMesh& written,
                             const geometry::TriangleMeshD& read) {
    ASSERT_EQ(read.num_vertices(), written.num_vertices());
    for (std::size_t v = 0; v < written.num_vertices(); ++v) {
        for (int k = 0; k < 3; ++k) {
            const auto rounded = static_cast<float>(read.positions[v][k]);
            ASSERT_EQ(std::bit_cast<std::uint32_t>(rounded),
                      std::bit_cast<std::uint32_t>(written.positions[v][k]))
                << "vertex " << v << " axis " << k << ": read " << read.positions[v][k]
                << ", wrote " << written.positions[v][k];
        }
    }
    ASSERT_EQ(read.triangles, written.triangles);
}

}  // namespace pliant::io::test
