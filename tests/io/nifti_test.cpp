#include "pliant/io/nifti.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/volume_io.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::TempDir;
using volume::Volume;
using volume::VoxelType;

constexpr std::size_t MAX = Volume::MAX_BYTES;

template <typename T>
void put(std::string& bytes, std::size_t at, T value) {
    std::memcpy(bytes.data() + at, &value, sizeof value);
}
template <typename T>
T get(const std::string& bytes, std::size_t at) {
    T value{};
    std::memcpy(&value, bytes.data() + at, sizeof value);
    return value;
}

// A NIfTI-2 file made by hand from the layout in nifti2.h (540-byte header, 4 extension bytes,
// then the voxels), independent of niftilib's writer: 3 × 2 × 2 int16, spacing 0.5 × 0.75 × 2,
// an sform turning i toward +y and j toward −x (90° about z) with the first voxel at (10, 20, 30).
std::string hand_made_nifti2() {
    std::string b(544, '\0');
    put<std::int32_t>(b, 0, 540);
    std::memcpy(b.data() + 4, "n+2\0\r\n\032\n", 8);
    put<std::int16_t>(b, 12, 4);   // datatype: DT_INT16
    put<std::int16_t>(b, 14, 16);  // bitpix
    const std::int64_t dim[8] = {3, 3, 2, 2, 1, 1, 1, 1};
    std::memcpy(b.data() + 16, dim, sizeof dim);
    const double pixdim[8] = {1, 0.5, 0.75, 2, 1, 1, 1, 1};
    std::memcpy(b.data() + 104, pixdim, sizeof pixdim);
    put<std::int64_t>(b, 168, 544);  // vox_offset
    put<double>(b, 176, 0.0);        // scl_slope: none
    put<std::int32_t>(b, 344, 0);    // qform_code
    put<std::int32_t>(b, 348, 1);    // sform_code: scanner
    const double srow_x[4] = {0, -0.75, 0, 10};
    const double srow_y[4] = {0.5, 0, 0, 20};
    const double srow_z[4] = {0, 0, 2, 30};
    std::memcpy(b.data() + 400, srow_x, sizeof srow_x);
    std::memcpy(b.data() + 432, srow_y, sizeof srow_y);
    std::memcpy(b.data() + 464, srow_z, sizeof srow_z);
    put<std::int32_t>(b, 500, 2);  // xyzt_units: mm
    for (std::int16_t v = 0; v < 12; ++v) {
        b.append(reinterpret_cast<const char*>(&v), 2);
    }
    return b;
}

TEST(Nifti, ReadsAHandMadeNifti2File) {
    TempDir dir;
    test::write_bytes(dir / "h.nii", hand_made_nifti2());
    // i along +y, j along −x: axis-aligned after swapping i and j and reversing (new) x.
    const Volume v = read_nifti(dir / "h.nii", MAX);
    EXPECT_TRUE(v.is_axis_aligned());
    EXPECT_EQ(v.type(), VoxelType::i16);
    EXPECT_EQ(v.dims(), (volume::Dims{2, 3, 2}));
    EXPECT_EQ(v.spacing(), (Vec3d{0.75, 0.5, 2.0}));
    // File voxel (i, j, k) holds i + 3 j + 6 k and sits at (10 − 0.75 j, 20 + 0.5 i, 30 + 2 k).
    const auto values = v.values<VoxelType::i16>();
    for (std::int64_t k = 0; k < 2; ++k) {
        for (std::int64_t j = 0; j < 2; ++j) {
            for (std::int64_t i = 0; i < 3; ++i) {
                const Vec3d p{10.0 - 0.75 * static_cast<double>(j),
                              20.0 + 0.5 * static_cast<double>(i),
                              30.0 + 2.0 * static_cast<double>(k)};
                // Find the voxel of v at p.
                const Vec3d u = p - v.origin();
                const auto x = static_cast<std::int64_t>(u.x / 0.75);
                const auto y = static_cast<std::int64_t>(u.y / 0.5);
                const auto z = static_cast<std::int64_t>(u.z / 2.0);
                EXPECT_EQ(v.voxel_center(x, y, z), p);
                EXPECT_EQ(values[static_cast<std::size_t>(v.index(x, y, z))], i + 3 * j + 6 * k);
            }
        }
    }
    // Truncated data and a truncated header name the file and the sizes.
    const std::string bytes = hand_made_nifti2();
    test::write_bytes(dir / "t.nii", bytes.substr(0, bytes.size() - 2));
    expect_io_error([&] { read_nifti(dir / "t.nii", MAX); }, {"t.nii", "truncated"});
    test::write_bytes(dir / "s.nii", bytes.substr(0, 300));
    expect_io_error([&] { read_nifti(dir / "s.nii", MAX); },
                    {"truncated NIfTI-2 header: expected 540 bytes, got 300"});
    std::string zero = bytes;
    put<std::int64_t>(zero, 16 + 2 * 8, 0);  // dim[2]
    test::write_bytes(dir / "z.nii", zero);
    expect_io_error([&] { read_nifti(dir / "z.nii", MAX); }, {"dim[2] is 0, expected at least 1"});
}

TEST(Nifti, Nifti2RoundTripsLargeDimsThatNifti1CannotHold) {
    TempDir dir;
    Volume v = Volume::allocate({40000, 2, 1}, VoxelType::u8, {0.1, 0.2, 0.3}, {1.5, -2.5, 3.5});
    v.values<VoxelType::u8>()[39999] = 7;
    try {
        write_nifti(dir / "one.nii", v, false, false);
        ADD_FAILURE() << "no error";
    } catch (const Unsupported& e) {
        EXPECT_NE(std::string(e.what()).find("NIfTI-2"), std::string::npos) << e.what();
    }
    write_nifti(dir / "two.nii.gz", v, true, true);
    const Volume back = read_nifti(dir / "two.nii.gz", MAX);
    EXPECT_EQ(back.dims(), v.dims());
    EXPECT_EQ(back.spacing(), v.spacing());  // doubles in NIfTI-2: exact
    EXPECT_NEAR(back.origin().x, 1.5, 1e-12);
    EXPECT_NEAR(back.origin().y, -2.5, 1e-12);
    EXPECT_EQ(back.values<VoxelType::u8>()[39999], 7);
}

TEST(Nifti, QformAloneAndShearedSformFallBackToTheQuaternion) {
    TempDir dir;
    Volume v = Volume::allocate({4, 3, 2}, VoxelType::f32, {1.0, 2.0, 3.0}, {0, 0, 0});
    const double t = 5.0 * std::numbers::pi / 180.0;
    v.set_direction({Vec3d{std::cos(t), std::sin(t), 0.0}, Vec3d{-std::sin(t), std::cos(t), 0.0},
                     Vec3d{0.0, 0.0, 1.0}});
    write_nifti(dir / "o.nii", v, false);
    const std::string bytes = test::read_bytes(dir / "o.nii");
    // NIfTI-1 layout: qform_code at 252, sform_code at 254, srow_x at 280.
    ASSERT_EQ(get<std::int16_t>(bytes, 252), 1);
    ASSERT_EQ(get<std::int16_t>(bytes, 254), 1);
    std::string qform_only = bytes;
    put<std::int16_t>(qform_only, 254, 0);
    test::write_bytes(dir / "q.nii", qform_only);
    std::string sheared = bytes;
    put<float>(sheared, 280 + 4, 0.7F);  // srow_x[1]: column j leans toward x
    test::write_bytes(dir / "s.nii", sheared);
    std::vector<std::string> warnings;
    const LogSink previous = set_log_sink([&](LogLevel level, std::string_view message) {
        if (level == LogLevel::warning) {
            warnings.emplace_back(message);
        }
    });
    const Volume q = read_nifti(dir / "q.nii", MAX);
    const Volume s = read_nifti(dir / "s.nii", MAX);
    set_log_sink(previous);
    for (const Volume* r : {&q, &s}) {
        EXPECT_FALSE(r->is_axis_aligned());
        for (std::size_t a = 0; a < 3; ++a) {
            EXPECT_LT(norm(r->direction()[a] - v.direction()[a]), 1e-6);
        }
        EXPECT_NEAR(r->spacing().y, 2.0, 1e-9);
    }
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("sheared"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("qform"), std::string::npos) << warnings[0];
    // Sheared and no qform: refused, saying why.
    put<std::int16_t>(sheared, 252, 0);
    test::write_bytes(dir / "n.nii", sheared);
    try {
        read_nifti(dir / "n.nii", MAX);
        ADD_FAILURE() << "no error";
    } catch (const Unsupported& e) {
        EXPECT_NE(std::string(e.what()).find("sheared"), std::string::npos) << e.what();
    }
}

TEST(Nifti, AxisAlignedFilesAreWrittenWithAnIdentityRotation) {
    // The bytes of an axis-aligned file do not depend on the orientation support: identity
    // quaternion, diagonal sform.
    TempDir dir;
    const Volume v = Volume::allocate({2, 2, 2}, VoxelType::u8, {0.5, 1.0, 2.0}, {-1.0, 0.0, 1.0});
    write_nifti(dir / "a.nii", v, false);
    const std::string bytes = test::read_bytes(dir / "a.nii");
    EXPECT_EQ(get<float>(bytes, 256), 0.0F);    // quatern_b
    EXPECT_EQ(get<float>(bytes, 280), 0.5F);    // srow_x[0]
    EXPECT_EQ(get<float>(bytes, 284), 0.0F);    // srow_x[1]
    EXPECT_EQ(get<float>(bytes, 292), -0.75F);  // srow_x[3]: the first voxel's centre
    EXPECT_EQ(bytes.size(), 352u + 8u);
}

}  // namespace
}  // namespace pliant::io
