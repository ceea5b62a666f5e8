#include "pliant/io/nifti.hpp"

#include <fmt/format.h>
#include <nifti2_io.h>
#include <zlib.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/volume_data.hpp"
#include "pliant/volume/reorient.hpp"

namespace pliant::io {

namespace {

using volume::VoxelType;

struct ImageFree {
    void operator()(nifti_image* nim) const { nifti_image_free(nim); }
};
using Image = std::unique_ptr<nifti_image, ImageFree>;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& message) {
    throw IoError(fmt::format("{}: {}", path.string(), message));
}

void quiet_niftilib() {
    static std::once_flag once;
    std::call_once(once, [] { nifti_set_debug_level(0); });
}

bool is_gzip_name(const std::string& name) {
    return name.size() > 3 && (name.ends_with(".gz") || name.ends_with(".GZ"));
}

struct ZnzClose {
    void operator()(znzptr* f) const {
        znzFile file = f;
        znzclose(file);
    }
};

VoxelType voxel_type(const std::filesystem::path& path, int datatype) {
    switch (datatype) {
        case DT_UINT8:
            return VoxelType::u8;
        case DT_INT16:
            return VoxelType::i16;
        case DT_UINT16:
            return VoxelType::u16;
        case DT_FLOAT32:
            return VoxelType::f32;
        case DT_RGBA32:
            return VoxelType::rgba8;
        default:
            throw Unsupported(fmt::format(
                "{}: NIfTI datatype {} ({}) is not supported, expected uint8, int16, uint16, "
                "float32 or RGBA32",
                path.string(), nifti_datatype_string(datatype), datatype));
    }
}

template <typename T>
void scale_into(std::span<T> in, std::span<float> out, double slope, double inter) {
    for (std::size_t i = 0; i < in.size(); ++i) {
        out[i] = static_cast<float>(static_cast<double>(in[i]) * slope + inter);
    }
}

// Checks the header (348 bytes for NIfTI-1 and Analyze, 540 for NIfTI-2) before niftilib sees
// it: niftilib prints "** ERROR" lines on stderr for some broken headers (whatever its debug
// level), and its failure says less than this. Reads through zlib, so .nii.gz and .nii alike; a
// byte-swapped header (big endian) is checked swapped. Analyze .hdr files (magic "ni1") pass too.
void check_header(const std::filesystem::path& path) {
    std::array<unsigned char, 540> h{};
    int got = 0;
    if (gzFile file = gzopen(path.c_str(), "rb"); file != nullptr) {
        got = gzread(file, h.data(), static_cast<unsigned>(h.size()));
        gzclose(file);
    }
    got = std::max(got, 0);
    const auto u32 = [&](std::size_t at, bool swap) {
        std::uint32_t v = 0;
        std::memcpy(&v, h.data() + at, 4);
        return swap ? __builtin_bswap32(v) : v;
    };
    const auto i16 = [&](std::size_t at, bool swap) {
        std::uint16_t v = 0;
        std::memcpy(&v, h.data() + at, 2);
        return static_cast<std::int16_t>(swap ? __builtin_bswap16(v) : v);
    };
    const auto i64 = [&](std::size_t at, bool swap) {
        std::uint64_t v = 0;
        std::memcpy(&v, h.data() + at, 8);
        return static_cast<std::int64_t>(swap ? __builtin_bswap64(v) : v);
    };
    if (got < 4) {
        fail(path, fmt::format("truncated NIfTI-1 header: expected 348 bytes, got {}", got));
    }
    const std::uint32_t size = u32(0, false);
    const bool swap = size != 348 && size != 540;
    const std::uint32_t header_size = swap ? u32(0, true) : size;
    if (header_size != 348 && header_size != 540) {
        fail(path, fmt::format("not a NIfTI file: sizeof_hdr is {}, expected 348 (NIfTI-1) or 540 "
                               "(NIfTI-2)",
                               static_cast<std::int32_t>(size)));
    }
    const bool nifti2 = header_size == 540;
    if (got < static_cast<int>(header_size)) {
        fail(path, fmt::format("truncated NIfTI-{} header: expected {} bytes, got {}",
                               nifti2 ? 2 : 1, header_size, got));
    }
    const std::int64_t ndim = nifti2 ? i64(16, swap) : i16(40, swap);
    if (ndim < 1 || ndim > 7) {
        fail(path, fmt::format("NIfTI dim[0] out of range, expected 1 to 7, got {}", ndim));
    }
    for (int d = 1; d <= ndim; ++d) {
        const std::int64_t n = nifti2 ? i64(16 + 8 * static_cast<std::size_t>(d), swap)
                                      : i16(40 + 2 * static_cast<std::size_t>(d), swap);
        if (n < 1) {
            fail(path, fmt::format("NIfTI dim[{}] is {}, expected at least 1", d, n));
        }
    }
}

// Where the header puts the grid: the sform (sform_code > 0), else the qform (qform_code > 0),
// else pixdim along the axes from (0, 0, 0). A sheared sform falls back to the qform (always a
// rotation) when there is one.
volume::GridPlacement placement(const std::filesystem::path& path, const nifti_image& nim) {
    volume::GridPlacement p;
    const auto from = [&](const nifti_dmat44& m, const char* which) {
        for (std::size_t r = 0; r < 3; ++r) {
            for (std::size_t c = 0; c < 4; ++c) {
                if (!std::isfinite(m.m[r][c])) {
                    fail(path, fmt::format("NIfTI {} has a non-finite entry [{}][{}]: {}", which, r,
                                           c, m.m[r][c]));
                }
            }
        }
        volume::GridPlacement q;
        q.centre0 = {m.m[0][3], m.m[1][3], m.m[2][3]};
        for (std::size_t c = 0; c < 3; ++c) {
            q.steps[c] = {m.m[0][c], m.m[1][c], m.m[2][c]};
            const double length = norm(q.steps[c]);
            if (!(length > 0)) {
                fail(path, fmt::format("NIfTI spacing of axis {} (the {}'s column {}): expected a "
                                       "finite number > 0, got {}",
                                       c, which, c, length));
            }
        }
        return q;
    };
    if (nim.sform_code > 0) {
        p = from(nim.sto_xyz, "sform");
        const double cosine = volume::max_axis_cosine(p);
        if (cosine <= volume::MAX_AXIS_COSINE) {
            // The sform holds floats: an oblique column's length is the spacing only to float
            // precision, and pixdim holds it exactly.
            const std::array<double, 3> pixdim{nim.dx, nim.dy, nim.dz};
            for (std::size_t c = 0; c < 3; ++c) {
                const Vec3d& step = p.steps[c];
                const double length = norm(step);
                const double along =
                    std::max({std::abs(step.x), std::abs(step.y), std::abs(step.z)});
                const bool oblique = along < length * (1.0 - 1e-12);
                if (oblique && std::isfinite(pixdim[c]) &&
                    std::abs(length - std::abs(pixdim[c])) <= 1e-5 * length) {
                    p.lengths[c] = std::abs(pixdim[c]);
                }
            }
            return p;
        }
        if (nim.qform_code <= 0) {
            throw Unsupported(fmt::format(
                "{}: NIfTI sform is sheared (its columns are not orthogonal: largest |cosine| "
                "{:.3g}) and there is no qform: a sheared grid cannot be placed without "
                "resampling it",
                path.string(), cosine));
        }
        log_warning("{}: the NIfTI sform is sheared (largest |cosine| {:.3g}); using the qform",
                    path.string(), cosine);
        return from(nim.qto_xyz, "qform");
    }
    if (nim.qform_code > 0) {
        return from(nim.qto_xyz, "qform");
    }
    const std::array<double, 3> spacing{nim.dx, nim.dy, nim.dz};
    for (std::size_t a = 0; a < 3; ++a) {
        if (!std::isfinite(spacing[a]) || spacing[a] <= 0) {
            fail(path, fmt::format("NIfTI spacing of axis {} (pixdim[{}]): expected a finite "
                                   "number > 0, got {}",
                                   a, a + 1, spacing[a]));
        }
    }
    p.steps = {Vec3d{spacing[0], 0, 0}, Vec3d{0, spacing[1], 0}, Vec3d{0, 0, spacing[2]}};
    return p;
}

}  // namespace

volume::Volume read_nifti(const std::filesystem::path& path, std::size_t max_bytes) {
    quiet_niftilib();
    const std::uint64_t size = detail::file_size(path);
    if (size == 0) {
        fail(path, "empty file, expected a NIfTI-1 header");
    }
    check_header(path);
    const Image nim(nifti_image_read(path.c_str(), 0));
    if (!nim) {
        fail(path,
             "not a readable NIfTI file (bad or truncated header, wrong magic, or a "
             "missing .img)");
    }
    const VoxelType stored = voxel_type(path, nim->datatype);

    // Dims: 3 spatial, a trailing dim of 1 allowed.
    if (nim->ndim < 1 || nim->ndim > 7) {
        fail(path, fmt::format("NIfTI dim[0] out of range, expected 1 to 7, got {}", nim->ndim));
    }
    for (int d = 4; d <= nim->ndim; ++d) {
        if (nim->dim[d] != 1) {
            throw Unsupported(fmt::format(
                "{}: NIfTI image with {} dims (dim[{}] = {}) is not supported, expected a 3D "
                "volume",
                path.string(), nim->ndim, d, nim->dim[d]));
        }
    }
    volume::Dims dims{1, 1, 1};
    for (int d = 1; d <= std::min<std::int64_t>(nim->ndim, 3); ++d) {
        dims[static_cast<std::size_t>(d - 1)] = nim->dim[d];
    }

    // Scaling: identity, or the result is f32.
    const double slope = nim->scl_slope;
    const double inter = nim->scl_inter;
    const bool scaled = std::isfinite(slope) && slope != 0.0 &&
                        (slope != 1.0 || (std::isfinite(inter) && inter != 0.0));
    if (scaled && stored == VoxelType::rgba8) {
        throw Unsupported(
            fmt::format("{}: NIfTI RGBA32 with scl_slope {} / scl_inter {} is not "
                        "supported",
                        path.string(), slope, inter));
    }
    const VoxelType result_type = scaled ? VoxelType::f32 : stored;
    const std::size_t stored_bytes = detail::check_declared_size(path, dims, stored, max_bytes);
    detail::check_declared_size(path, dims, result_type, max_bytes);

    const volume::GridPlacement grid = placement(path, *nim);

    // The image file: size check (uncompressed) before allocating.
    const std::filesystem::path image_path = nim->iname != nullptr ? nim->iname : path.string();
    const bool gz = is_gzip_name(image_path.string());
    const auto offset = static_cast<std::uint64_t>(std::max<std::int64_t>(0, nim->iname_offset));
    const std::uint64_t image_size = detail::file_size(image_path);
    if (!gz && (image_size < offset || image_size - offset < stored_bytes)) {
        fail(image_path,
             fmt::format("truncated voxel data: the header declares {} {} voxels, "
                         "expected {} bytes after byte offset {}, got {}",
                         detail::dims_text(dims), nifti_datatype_string(nim->datatype),
                         stored_bytes, offset, image_size > offset ? image_size - offset : 0));
    }
    if (gz && image_size * detail::MAX_INFLATE_RATIO + 1024 < stored_bytes + offset) {
        fail(image_path, fmt::format("the header declares {} bytes of voxel data but the "
                                     "compressed file has only {} bytes: truncated or lying",
                                     stored_bytes, image_size));
    }
    volume::Volume volume = volume::Volume::allocate(dims, stored, {1, 1, 1}, {0, 0, 0}, max_bytes);
    {
        std::unique_ptr<znzptr, ZnzClose> file(znzopen(image_path.c_str(), "rb", gz ? 1 : 0));
        if (!file) {
            fail(image_path, "cannot open the NIfTI image data");
        }
        if (znzseek(file.get(), static_cast<znz_off_t>(offset), SEEK_SET) < 0) {  // gz: new offset
            fail(image_path, fmt::format("cannot seek to the voxel data at byte {}", offset));
        }
        std::span<std::byte> out = volume.bytes();
        std::size_t done = 0;
        while (done < out.size()) {
            const std::size_t chunk =
                std::min<std::size_t>(out.size() - done, std::size_t{1} << 28);
            const std::size_t n = znzread(out.data() + done, 1, chunk, file.get());
            if (n == 0) {
                break;
            }
            done += n;
        }
        if (done != out.size()) {
            fail(image_path,
                 fmt::format("truncated voxel data, expected {} bytes, got {}", out.size(), done));
        }
    }
    if (nim->byteorder != nifti_short_order()) {
        detail::swap_channel_bytes(volume);
    }
    volume = volume::place_nearest_axes(std::move(volume), grid);
    if (!scaled) {
        return volume;
    }
    volume::Volume result = volume::Volume::allocate(volume.dims(), VoxelType::f32,
                                                     volume.spacing(), volume.origin(), max_bytes);
    result.set_direction(volume.direction());
    std::span<float> out = result.values<VoxelType::f32>();
    switch (stored) {
        case VoxelType::u8:
            scale_into(volume.values<VoxelType::u8>(), out, slope, inter);
            break;
        case VoxelType::i16:
            scale_into(volume.values<VoxelType::i16>(), out, slope, inter);
            break;
        case VoxelType::u16:
            scale_into(volume.values<VoxelType::u16>(), out, slope, inter);
            break;
        default:
            scale_into(volume.values<VoxelType::f32>(), out, slope, inter);
            break;
    }
    return result;
}

void write_nifti(const std::filesystem::path& path, const volume::Volume& volume, bool gzip,
                 bool nifti2) {
    quiet_niftilib();
    if (volume.empty()) {
        throw InvalidInput(fmt::format("write_nifti: {}: the volume is empty", path.string()));
    }
    int datatype = 0;
    switch (volume.type()) {
        case VoxelType::u8:
            datatype = DT_UINT8;
            break;
        case VoxelType::i16:
            datatype = DT_INT16;
            break;
        case VoxelType::u16:
            datatype = DT_UINT16;
            break;
        case VoxelType::f32:
            datatype = DT_FLOAT32;
            break;
        case VoxelType::rgba8:
            datatype = DT_RGBA32;
            break;
        case VoxelType::rgba32f:
            throw Unsupported(
                fmt::format("{}: NIfTI has no RGBA float type: write rgba32f "
                            "volumes as NRRD, MetaImage or raw + JSON",
                            path.string()));
    }
    const volume::Dims& d = volume.dims();
    if (!nifti2) {
        for (const std::int64_t n : d) {
            if (n > 32767) {
                throw Unsupported(fmt::format(
                    "{}: NIfTI-1 dims are at most 32767, got {} (write NIfTI-2 instead)",
                    path.string(), detail::dims_text(d)));
            }
        }
    }
    const std::int64_t dims[8] = {3, d[0], d[1], d[2], 1, 1, 1, 1};
    const Image nim(nifti_make_new_nim(dims, datatype, 0));
    if (!nim) {
        throw InternalError("write_nifti: nifti_make_new_nim failed");
    }
    // NIfTI-1 stores floats, NIfTI-2 doubles.
    const auto stored = [nifti2](double v) {
        return nifti2 ? v : static_cast<double>(static_cast<float>(v));
    };
    const Vec3d& s = volume.spacing();
    const Vec3d& o = volume.origin();
    nim->dx = nim->pixdim[1] = stored(s.x);
    nim->dy = nim->pixdim[2] = stored(s.y);
    nim->dz = nim->pixdim[3] = stored(s.z);
    nim->xyz_units = NIFTI_UNITS_MM;
    nim->scl_slope = 0.0F;
    nim->scl_inter = 0.0F;
    nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
    nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
    for (auto& row : nim->sto_xyz.m) {
        for (auto& entry : row) {
            entry = 0.0;
        }
    }
    nim->sto_xyz.m[3][3] = 1.0;
    if (volume.is_axis_aligned()) {
        // Identity rotation; the translation is the first voxel's centre.
        const std::array<double, 3> spacing{s.x, s.y, s.z};
        const std::array<double, 3> centre0{o.x + 0.5 * s.x, o.y + 0.5 * s.y, o.z + 0.5 * s.z};
        nim->quatern_b = nim->quatern_c = nim->quatern_d = 0.0;
        nim->qfac = 1.0;
        nim->qoffset_x = stored(centre0[0]);
        nim->qoffset_y = stored(centre0[1]);
        nim->qoffset_z = stored(centre0[2]);
        for (std::size_t a = 0; a < 3; ++a) {
            nim->sto_xyz.m[a][a] = stored(spacing[a]);
            nim->sto_xyz.m[a][3] = stored(centre0[a]);
        }
    } else {
        // sform: columns direction × spacing, translation the first voxel's centre; the qform is
        // the same rotation as a quaternion (qfac −1 for a reflection).
        const volume::Direction& dir = volume.direction();
        const Vec3d centre0 = volume.world_from_grid({0.5, 0.5, 0.5});
        const std::array<double, 3> spacing{s.x, s.y, s.z};
        for (std::size_t c = 0; c < 3; ++c) {
            for (int r = 0; r < 3; ++r) {
                nim->sto_xyz.m[r][c] = dir[c][r] * spacing[c];
            }
        }
        nim->sto_xyz.m[0][3] = centre0.x;
        nim->sto_xyz.m[1][3] = centre0.y;
        nim->sto_xyz.m[2][3] = centre0.z;
        double qx = 0, qy = 0, qz = 0, dx = 0, dy = 0, dz = 0;
        nifti_dmat44_to_quatern(nim->sto_xyz, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d,
                                &qx, &qy, &qz, &dx, &dy, &dz, &nim->qfac);
        nim->qoffset_x = centre0.x;
        nim->qoffset_y = centre0.y;
        nim->qoffset_z = centre0.z;
    }
    std::string bytes;
    if (nifti2) {
        nim->nifti_type = NIFTI_FTYPE_NIFTI2_1;
        nifti_2_header header{};
        if (nifti_convert_nim2n2hdr(nim.get(), &header) != 0) {
            throw InternalError("write_nifti: nifti_convert_nim2n2hdr failed");
        }
        static_assert(sizeof(nifti_2_header) == 540);
        header.vox_offset = 544;
        bytes.assign(544 + volume.size_bytes(), '\0');
        std::memcpy(bytes.data(), &header, sizeof header);
    } else {
        nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
        nifti_1_header header{};
        if (nifti_convert_nim2n1hdr(nim.get(), &header) != 0) {
            throw InternalError("write_nifti: nifti_convert_nim2n1hdr failed");
        }
        static_assert(sizeof(nifti_1_header) == 348);
        header.vox_offset = 352.0F;
        bytes.assign(352 + volume.size_bytes(), '\0');
        std::memcpy(bytes.data(), &header, sizeof header);
    }
    // After the header: the 4-byte extension flag, 0 (no extensions), then the voxels.
    std::memcpy(bytes.data() + (bytes.size() - volume.size_bytes()), volume.bytes().data(),
                volume.size_bytes());
    write_file_atomically(path, [&](std::ostream& out) {
        if (gzip) {
            detail::write_gzip(out, std::as_bytes(std::span<const char>(bytes)));
        } else {
            out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        }
    });
}

}  // namespace pliant::io
