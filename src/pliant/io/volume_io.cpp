#include "pliant/io/volume_io.hpp"

#include <fmt/format.h>

#include <cctype>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/io/inv3.hpp"
#include "pliant/io/nifti.hpp"
#include "pliant/io/nrrd.hpp"
#include "pliant/io/raw_volume.hpp"

namespace pliant::io {

namespace {

bool ends_with(const std::string& name, std::string_view suffix) {
    return name.size() > suffix.size() && name.ends_with(suffix);
}

}  // namespace

VolumeFormat volume_format(const std::filesystem::path& path) {
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
    throw Unsupported(fmt::format(
        "{}: unknown volume file extension, expected .nrrd, .nhdr, .nii, .nii.gz, .hdr, .json, "
        ".raw, .raw.gz or .inv3",
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
    }
    return "?";
}

volume::Volume read_volume(const std::filesystem::path& path, const ReadVolumeOptions& options) {
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
    }
    throw InternalError("read_volume: unhandled format");
}

void check_volume_writable(const std::filesystem::path& path, volume::VoxelType type) {
    const VolumeFormat format = volume_format(path);
    if (format == VolumeFormat::analyze_hdr || format == VolumeFormat::inv3) {
        throw Unsupported(
            fmt::format("{}: {} is read only, expected .nrrd, .nhdr, .nii, .nii.gz or .json/.raw",
                        path.string(), name(format)));
    }
    if ((format == VolumeFormat::nifti || format == VolumeFormat::nifti_gz) &&
        type == volume::VoxelType::rgba32f) {
        throw Unsupported(fmt::format(
            "{}: NIfTI-1 has no RGBA float type: write rgba32f volumes as NRRD or raw + JSON",
            path.string()));
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
            write_nifti(path, volume, false);
            return;
        case VolumeFormat::nifti_gz:
            write_nifti(path, volume, true);
            return;
        case VolumeFormat::raw_json:
            write_raw_volume(path, volume, options.gzip);
            return;
        case VolumeFormat::analyze_hdr:
        case VolumeFormat::inv3:
            return;  // refused by check_volume_writable
    }
}

}  // namespace pliant::io
