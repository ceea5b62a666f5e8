// Volume files: read_volume / write_volume dispatch on the path (volume_format).
//
//   .nrrd           NRRD, attached header (io/nrrd.hpp); read: raw or gzip, little or big endian
//   .nhdr           NRRD, detached header + data file named by `data file:`
//   .nii / .nii.gz  NIfTI-1 and NIfTI-2 through niftilib (io/nifti.hpp); .hdr (+ .img) read only
//   .mha / .mhd     MetaImage (io/metaimage.hpp): header + data, or header + .raw / .zraw
//   .json / .raw    raw voxels + JSON sidecar (io/raw_volume.hpp): name either file
//   .inv3           InVesalius 3 project (gzip tar with main.plist + int16 matrix.dat), read only
//   folder, .dcm    DICOM series through GDCM (io/dicom.hpp), read only
//   .vdb            OpenVDB through libopenvdb (io/openvdb.hpp): a float grid (+ a colour grid)
//
// Conventions (docs/formats.md, "Volumes"): pliant's origin is the corner of the voxel box;
// voxel centres are at origin + D · (i + 0.5) · spacing (volume/volume.hpp). The files' first
// voxel centres (NRRD `space origin`, the NIfTI qform/sform translation, MetaImage Offset, DICOM
// ImagePositionPatient) are converted; the world is RAS+ (LPS files are converted). Grids are
// re-indexed to the nearest axes (exact flips and axis swaps); an oblique grid keeps its
// direction, and read_volume resamples it to an axis-aligned grid unless
// ReadVolumeOptions::orientation is keep (render, dataset, view and volume info keep it).
//
// Limits: every reader checks the declared size against ReadVolumeOptions::max_bytes and against
// the bytes actually in the file BEFORE allocating. Errors: IoError "<path>: <what>, expected X,
// got Y" for broken or lying files; Unsupported for valid files using features pliant does not
// read (other voxel types, shear, 4D series). Writes are atomic (io/atomic_file.hpp).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

// What read_volume does with an oblique volume (one whose direction is not the identity after
// the reader's exact flips and axis swaps).
enum class Orientation {
    // Resample it onto an axis-aligned grid covering it (volume::resample_to_axis_aligned at its
    // smallest spacing; outside: the smallest value of a scalar volume, 0 for RGBA) and say so
    // once through log_info. What tet grids and the deform pipeline need (the ray caster renders
    // an oriented volume as it lies: `pliant render` reads with keep).
    axis_aligned,
    // Return it with its direction (volume info, conversion between formats that hold it).
    keep,
};

struct ReadVolumeOptions {
    // Largest voxel data (bytes) a reader may allocate; larger declared sizes are refused.
    std::size_t max_bytes = volume::Volume::MAX_BYTES;
    Orientation orientation = Orientation::axis_aligned;
    // DICOM: the SeriesInstanceUID to read from a folder holding several series; empty: the
    // series with the most slices (io/dicom.hpp). Ignored by the other formats.
    std::string series_uid{};
    // OpenVDB: the float grid to read; empty: "density", else the only float grid
    // (io/openvdb.hpp). Ignored by the other formats.
    std::string grid{};
};

struct WriteVolumeOptions {
    // gzip-compress the voxel data (NRRD, raw + sidecar, MetaImage). NIfTI chooses by extension
    // (.nii.gz); gzip with a .nii name is InvalidInput.
    bool gzip = false;
    // NIfTI: write NIfTI-2 (64-bit dims, double placement) instead of NIfTI-1. NIfTI-1 cannot
    // hold dims above 32767: those need this flag.
    bool nifti2 = false;
};

enum class VolumeFormat {
    nrrd,
    nhdr,
    nifti,
    nifti_gz,
    analyze_hdr,
    raw_json,
    inv3,
    metaimage,      // .mha
    metaimage_mhd,  // .mhd + data file
    dicom,          // a folder, a .dcm / .dicom / .ima file, or any file with a DICM marker
    openvdb,        // .vdb
};

// The format for a path: a folder is DICOM; a file by its case-insensitive extension, else DICOM
// when it has the DICM marker; Unsupported listing the extensions when nothing matches.
VolumeFormat volume_format(const std::filesystem::path& path);
std::string_view name(VolumeFormat format);

volume::Volume read_volume(const std::filesystem::path& path,
                           const ReadVolumeOptions& options = {});

// What read_volume does under Orientation::axis_aligned: an axis-aligned volume is returned as it
// is; an oblique one is resampled (see Orientation) and one info line naming `path` is logged.
// InvalidInput when the result would exceed max_bytes.
volume::Volume to_axis_aligned(const std::filesystem::path& path, volume::Volume volume,
                               std::size_t max_bytes = volume::Volume::MAX_BYTES);

// Unsupported for read-only formats (.inv3, .hdr, DICOM) and for voxel types a format cannot
// store (NIfTI has no RGBA float). The direction is written by NRRD, NIfTI, MetaImage, raw +
// JSON and OpenVDB (every writable format).
void write_volume(const std::filesystem::path& path, const volume::Volume& volume,
                  const WriteVolumeOptions& options = {});

// Throws what write_volume would for the name and voxel type alone (Unsupported for read-only
// formats and types the format cannot store), so that long runs fail before they start.
void check_volume_writable(const std::filesystem::path& path, volume::VoxelType type);

}  // namespace pliant::io
