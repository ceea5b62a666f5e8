// DICOM series through GDCM (Debian libgdcm-dev): a folder of slices (or a list of files, or one
// multi-frame file) into one Volume. Reading only; pliant writes no DICOM.
//
// Which files: a folder is searched recursively for Part-10 files (the "DICM" marker at byte
// 128) and files named *.dcm, *.dicom, *.ima; their headers are scanned (gdcm::Scanner, no pixel
// data) and grouped by SeriesInstanceUID. Files GDCM cannot parse, and objects without an image
// (DICOMDIR, reports), are skipped in a folder and are errors in an explicit list. A path to one
// file reads the series that file belongs to, from the files of its folder.
//
// Which series: options.series_uid, else the largest (most voxels; then most files; then the
// smallest UID), with an info line naming the others when there are several.
// list_dicom_series lists them all.
//
// Geometry: slices are sorted by their position along the slice normal
// (ImagePositionPatient · (row × column cosines)), not by file name or InstanceNumber; the slice
// spacing is the mean step between positions; in-plane spacing from PixelSpacing (else
// ImagerPixelSpacing, else 1 with a warning); the direction from ImageOrientationPatient.
// Coordinates are converted from DICOM's LPS to pliant's RAS+ world (x and y negated) and the
// grid is re-indexed to the nearest axes (volume/reorient.hpp): a standard axial series is
// axis-aligned, an oblique one keeps its direction. Slices offset within their plane (gantry
// tilt) are placed along the normal with a warning stating the angle. Without any
// ImagePositionPatient (secondary captures) slices are ordered by InstanceNumber and spaced by
// SpacingBetweenSlices, else SliceThickness, else 1, with a warning.
//
// Values: RescaleSlope and RescaleIntercept (per slice) are applied, so CT is in Hounsfield
// units. The voxel type: u8 or u16 when there is no rescaling and the data is stored so; i16
// when every slope and intercept is an integer and the rescaled values fit in int16 (CT); f32
// otherwise. Grey-scale data only (SamplesPerPixel 1): colour is Unsupported. Compressed transfer
// syntaxes are whatever gdcm::ImageReader decodes (JPEG baseline and lossless, JPEG-LS,
// JPEG 2000, RLE, deflate).
//
// Errors: IoError for what cannot be read (no DICOM image in a folder, a listed file that is not
// DICOM, undecodable pixel data, a folder that does not exist); InvalidInput for a series that is
// not one regular grid, each naming the files involved: slices of different sizes, pixel
// spacings or orientations, two slices at one position, a missing slice (a gap that is a whole
// multiple of the others), uneven spacing (the two gaps that differ), an unknown series_uid
// (listing the series there are). The size is checked against max_bytes before the pixel data
// is read. Unsupported when pliant was built without GDCM.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "pliant/volume/volume.hpp"

namespace pliant::io {

struct DicomSeriesInfo {
    std::string uid;          // SeriesInstanceUID ("" when the files have none)
    std::string description;  // SeriesDescription ("" when absent)
    std::string modality;     // Modality (CT, MR, PT, …; "" when absent)
    std::int64_t num_files = 0;
    volume::Dims dims{0, 0, 0};        // columns, rows, slices (frames of a multi-frame file)
    std::filesystem::path first_file;  // the first of its files in name order
};

struct DicomReadOptions {
    std::string series_uid{};  // empty: the largest series
    std::size_t max_bytes = volume::Volume::MAX_BYTES;
    // The longest GDCM may take over one file (seconds); its child process is killed after.
    double gdcm_seconds = 60.0;
};

// False when pliant was built without GDCM (then the functions below throw Unsupported).
bool has_dicom_support();

// Whether the file starts like a DICOM Part-10 file ("DICM" at byte 128).
bool is_dicom_file(const std::filesystem::path& path);

// The series in a folder (recursively), in a file's folder, or in a list of files: largest first
// (the order read_dicom_series chooses by), then by UID.
std::vector<DicomSeriesInfo> list_dicom_series(const std::filesystem::path& path);
std::vector<DicomSeriesInfo> list_dicom_series(std::span<const std::filesystem::path> files);

// The UID of the series read_dicom_series(path, {series_uid}) reads (scans headers only).
std::string chosen_dicom_series(const std::filesystem::path& path, const std::string& series_uid);

volume::Volume read_dicom_series(const std::filesystem::path& path,
                                 const DicomReadOptions& options = {});
volume::Volume read_dicom_series(std::span<const std::filesystem::path> files,
                                 const DicomReadOptions& options = {});

}  // namespace pliant::io
