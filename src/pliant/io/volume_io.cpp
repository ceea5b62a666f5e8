#include "pliant/io/volume_io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/core/log.hpp"
#include "pliant/io/dicom.hpp"
#include "pliant/io/inv3.hpp"
#include "pliant/io/metaimage.hpp"
#include "pliant/io/nifti.hpp"
#include "pliant/io/nrrd.hpp"
#include "pliant/io/openvdb.hpp"
#include "pliant/io/raw_volume.hpp"
#include "pliant/volume/reorient.hpp"

namespace pliant::io {

namespace {

bool ends_with(const std::string& name, std::string_view suffix) {
    return name.size() > suffix.size() && name.ends_with(suffix);
}

}  // namespace

VolumeFormat volume_format(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        return VolumeFormat::dicom;
    }
    std::string name = path.filename().string();
    for (char& c : name) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    if (ends_with(name, ".nrrd")) {
        return VolumeFormat::nrrd;
    }
    if (ends_with(name, ".nhdr")) {
        return VolumeFormat::nhdr;
    }
    if (ends_with(name, ".nii.gz")) {
        return VolumeFormat::nifti_gz;
    }
    if (ends_with(name, ".nii")) {
        return VolumeFormat::nifti;
    }
    if (ends_with(name, ".hdr")) {
        return VolumeFormat::analyze_hdr;
    }
    if (ends_with(name, ".json") || ends_with(name, ".raw") || ends_with(name, ".raw.gz")) {
        return VolumeFormat::raw_json;
    }
    if (ends_with(name, ".inv3")) {
        return VolumeFormat::inv3;
    }
    if (ends_with(name, ".mha")) {
        return VolumeFormat::metaimage;
    }
    if (ends_with(name, ".mhd")) {
        return VolumeFormat::metaimage_mhd;
    }
    if (ends_with(name, ".vdb")) {
        return VolumeFormat::openvdb;
    }
    if (ends_with(name, ".dcm") || ends_with(name, ".dicom") || ends_with(name, ".ima") ||
        is_dicom_file(path)) {
        return VolumeFormat::dicom;
    }
    throw Unsupported(fmt::format(
        "{}: unknown volume file extension, expected .nrrd, .nhdr, .nii, .nii.gz, .hdr, .mha, "
        ".mhd, .json, .raw, .raw.gz, .inv3, .vdb, .dcm or a folder of DICOM files",
        path.string()));
}

std::string_view name(VolumeFormat format) {
    switch (format) {
        case VolumeFormat::nrrd:
            return "nrrd";
        case VolumeFormat::nhdr:
            return "nhdr";
        case VolumeFormat::nifti:
            return "nifti";
        case VolumeFormat::nifti_gz:
            return "nifti-gz";
        case VolumeFormat::analyze_hdr:
            return "nifti-hdr";
        case VolumeFormat::raw_json:
            return "raw-json";
        case VolumeFormat::inv3:
            return "inv3";
        case VolumeFormat::metaimage:
            return "metaimage";
        case VolumeFormat::metaimage_mhd:
            return "metaimage-mhd";
        case VolumeFormat::dicom:
            return "dicom";
        case VolumeFormat::openvdb:
            return "openvdb";
    }
    return "?";
}

namespace {

volume::Volume read_as_stored(const std::filesystem::path& path, const ReadVolumeOptions& options) {
    switch (volume_format(path)) {
        case VolumeFormat::nrrd:
        case VolumeFormat::nhdr:
            return read_nrrd(path, options.max_bytes);
        case VolumeFormat::nifti:
        case VolumeFormat::nifti_gz:
        case VolumeFormat::analyze_hdr:
            return read_nifti(path, options.max_bytes);
        case VolumeFormat::raw_json:
            return read_raw_volume(path, options.max_bytes);
        case VolumeFormat::inv3:
            return read_inv3(path, options.max_bytes);
        case VolumeFormat::metaimage:
        case VolumeFormat::metaimage_mhd:
            return read_metaimage(path, options.max_bytes);
        case VolumeFormat::dicom:
            return read_dicom_series(path, DicomReadOptions{.series_uid = options.series_uid,
                                                            .max_bytes = options.max_bytes});
        case VolumeFormat::openvdb:
            return read_openvdb(path, options.max_bytes, options.grid);
    }
    throw InternalError("read_volume: unhandled format");
}

// The smallest finite value of a scalar volume (0 for RGBA): what lies outside an oblique volume
// after resampling (air in CT, background in MRI).
double background_value(const volume::Volume& v) {
    const auto smallest = [](auto values) {
        double lo = std::numeric_limits<double>::infinity();
        for (const auto x : values) {
            const auto d = static_cast<double>(x);
            if (d < lo) {
                lo = d;
            }
        }
        return std::isfinite(lo) ? lo : 0.0;
    };
    switch (v.type()) {
        case volume::VoxelType::u8:
            return smallest(v.values<volume::VoxelType::u8>());
        case volume::VoxelType::i16:
            return smallest(v.values<volume::VoxelType::i16>());
        case volume::VoxelType::u16:
            return smallest(v.values<volume::VoxelType::u16>());
        case volume::VoxelType::f32:
            return smallest(v.values<volume::VoxelType::f32>());
        case volume::VoxelType::rgba8:
        case volume::VoxelType::rgba32f:
            return 0.0;
    }
    return 0.0;
}

}  // namespace

volume::Volume to_axis_aligned(const std::filesystem::path& path, volume::Volume volume,
                               std::size_t max_bytes) {
    if (volume.is_axis_aligned()) {
        return volume;
    }
    volume::AxisAlignedOptions options;
    options.outside = background_value(volume);
    options.max_bytes = max_bytes;
    volume::Volume out = volume::resample_to_axis_aligned(volume, options);
    const volume::Direction& d = volume.direction();
    double largest_angle = 0.0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double c = std::clamp(d[a][static_cast<int>(a)], -1.0, 1.0);
        largest_angle = std::max(largest_angle, std::acos(c) * 180.0 / std::numbers::pi);
    }
    log_info(
        "{}: the grid is oblique (an axis {:.2f}° from the world axes): resampled to an "
        "axis-aligned {}x{}x{} grid at spacing {:.4g} (trilinear; outside: {:g})",
        path.string(), largest_angle, out.dims()[0], out.dims()[1], out.dims()[2], out.spacing().x,
        options.outside);
    return out;
}

volume::Volume read_volume(const std::filesystem::path& path, const ReadVolumeOptions& options) {
    volume::Volume volume = read_as_stored(path, options);
    if (options.orientation == Orientation::keep) {
        return volume;
    }
    return to_axis_aligned(path, std::move(volume), options.max_bytes);
}

void check_volume_writable(const std::filesystem::path& path, volume::VoxelType type) {
    const VolumeFormat format = volume_format(path);
    if (format == VolumeFormat::analyze_hdr || format == VolumeFormat::inv3 ||
        format == VolumeFormat::dicom) {
        throw Unsupported(fmt::format(
            "{}: {} is read only, expected .nrrd, .nhdr, .nii, .nii.gz, .mha, .mhd, .vdb or "
            ".json/.raw",
            path.string(), name(format)));
    }
    if ((format == VolumeFormat::nifti || format == VolumeFormat::nifti_gz) &&
        type == volume::VoxelType::rgba32f) {
        throw Unsupported(fmt::format(
            "{}: NIfTI has no RGBA float type: write rgba32f volumes as NRRD, MetaImage or raw + "
            "JSON",
            path.string()));
    }
    if (format == VolumeFormat::openvdb && !has_openvdb_support()) {
        write_openvdb(path, volume::Volume{});  // throws Unsupported, naming the packages
    }
}

void write_volume(const std::filesystem::path& path, const volume::Volume& volume,
                  const WriteVolumeOptions& options) {
    check_volume_writable(path, volume.type());
    const VolumeFormat format = volume_format(path);
    switch (format) {
        case VolumeFormat::nrrd:
        case VolumeFormat::nhdr:
            write_nrrd(path, volume, options.gzip, format == VolumeFormat::nhdr);
            return;
        case VolumeFormat::nifti:
            if (options.gzip) {
                throw InvalidInput(fmt::format(
                    "write_volume: {}: gzip for NIfTI is chosen by the name, expected a .nii.gz "
                    "name, got .nii",
                    path.string()));
            }
            write_nifti(path, volume, false, options.nifti2);
            return;
        case VolumeFormat::nifti_gz:
            write_nifti(path, volume, true, options.nifti2);
            return;
        case VolumeFormat::raw_json:
            write_raw_volume(path, volume, options.gzip);
            return;
        case VolumeFormat::metaimage:
        case VolumeFormat::metaimage_mhd:
            write_metaimage(path, volume, options.gzip, format == VolumeFormat::metaimage_mhd);
            return;
        case VolumeFormat::openvdb:
            write_openvdb(path, volume);
            return;
        case VolumeFormat::analyze_hdr:
        case VolumeFormat::inv3:
        case VolumeFormat::dicom:
            return;  // refused by check_volume_writable
    }
}

}  // namespace pliant::io
