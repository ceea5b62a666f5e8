// Writes synthetic DICOM series with GDCM for the DICOM tests (tests/io/dicom_test.cpp and the
// CLI's, tests/integration): no network, no data files. A CT-like phantom — air at −1024 HU, a
// soft-tissue ellipse at 40 HU, a bone sphere at 1500 HU — stored as unsigned 16-bit values with
// RescaleIntercept −1024 and RescaleSlope 1, one file per slice, written in shuffled order under
// shuffled names with shuffled InstanceNumbers (so that only ImagePositionPatient orders them).
// Links GDCM (target pliant_gdcm).
#pragma once

#include <gdcmAttribute.h>
#include <gdcmImage.h>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageWriter.h>
#include <gdcmMediaStorage.h>
#include <gdcmTrace.h>
#include <gdcmUIDGenerator.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace pliant::test {

struct DicomSeriesSpec {
    int columns = 32;
    int rows = 32;
    int slices = 16;
    double row_spacing = 0.8;     // PixelSpacing[0]: between rows (along the column cosines), mm
    double column_spacing = 0.7;  // PixelSpacing[1]: between columns (along the row cosines), mm
    double slice_step = 2.5;      // between slice positions along the normal, mm
    std::array<double, 3> position0{-12.0, -11.0, 40.0};  // IPP of slice 0 (LPS, mm)
    std::array<double, 6> orientation{1, 0, 0, 0, 1, 0};  // IOP: row, column cosines
    double intercept = -1024.0;
    double slope = 1.0;
    std::string series_uid;  // empty: a new UID
    std::string description = "phantom";
    std::string modality = "CT";
    // Compressed transfer syntax (gdcm::ImageChangeTransferSyntax); Explicit VR Little Endian
    // when it is ExplicitVRLittleEndian.
    gdcm::TransferSyntax::TSType syntax = gdcm::TransferSyntax::ExplicitVRLittleEndian;
};

// The phantom in Hounsfield units at voxel (i, j, k) of a spec's grid.
inline double phantom_hu(const DicomSeriesSpec& spec, int i, int j, int k) {
    const double x = (i + 0.5) / spec.columns - 0.5;
    const double y = (j + 0.5) / spec.rows - 0.5;
    const double z = (k + 0.5) / spec.slices - 0.5;
    if (x * x + y * y + z * z < 0.3 * 0.3) {
        return 1500.0;
    }
    if ((x * x) / 0.2 + (y * y) / 0.16 < 1.0) {
        return 40.0;
    }
    return -1024.0;
}

inline std::array<double, 3> slice_normal(const DicomSeriesSpec& spec) {
    const auto& o = spec.orientation;
    return {o[1] * o[5] - o[2] * o[4], o[2] * o[3] - o[0] * o[5], o[0] * o[4] - o[1] * o[3]};
}

// Writes slice k of the spec (at distance `along` from position0 along the normal) to `path`,
// with InstanceNumber `instance`.
inline void write_dicom_slice(const std::filesystem::path& path, const DicomSeriesSpec& spec,
                              const std::string& series_uid, const std::string& study_uid, int k,
                              double along, int instance) {
    gdcm::Trace::WarningOff();  // GDCM notes on stderr what the writer fills in itself
    gdcm::SmartPointer<gdcm::Image> image = new gdcm::Image;
    image->SetNumberOfDimensions(2);
    image->SetDimension(0, static_cast<unsigned>(spec.columns));
    image->SetDimension(1, static_cast<unsigned>(spec.rows));
    image->SetPixelFormat(gdcm::PixelFormat::UINT16);
    image->SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    const std::array<double, 3> n = slice_normal(spec);
    for (unsigned a = 0; a < 3; ++a) {
        image->SetOrigin(a, spec.position0[a] + along * n[a]);
    }
    image->SetDirectionCosines(spec.orientation.data());
    image->SetSpacing(0, spec.column_spacing);
    image->SetSpacing(1, spec.row_spacing);
    image->SetSpacing(2, spec.slice_step);
    image->SetIntercept(spec.intercept);
    image->SetSlope(spec.slope);
    std::vector<std::uint16_t> pixels(static_cast<std::size_t>(spec.columns * spec.rows));
    for (int j = 0; j < spec.rows; ++j) {
        for (int i = 0; i < spec.columns; ++i) {
            const double stored = (phantom_hu(spec, i, j, k) - spec.intercept) / spec.slope;
            pixels[static_cast<std::size_t>(j * spec.columns + i)] =
                static_cast<std::uint16_t>(std::lround(stored));
        }
    }
    gdcm::DataElement data(gdcm::Tag(0x7fe0, 0x0010));
    data.SetByteValue(reinterpret_cast<const char*>(pixels.data()),
                      static_cast<std::uint32_t>(pixels.size() * 2));
    image->SetDataElement(data);
    image->SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);

    gdcm::ImageWriter writer;
    if (spec.syntax != gdcm::TransferSyntax::ExplicitVRLittleEndian) {
        gdcm::ImageChangeTransferSyntax change;
        change.SetTransferSyntax(spec.syntax);
        change.SetInput(*image);
        if (!change.Change()) {
            throw std::runtime_error("GDCM cannot compress to " +
                                     std::string(gdcm::TransferSyntax::GetTSString(spec.syntax)));
        }
        writer.SetImage(change.GetOutput());
    } else {
        writer.SetImage(*image);
    }
    gdcm::DataSet& ds = writer.GetFile().GetDataSet();
    const auto put = [&](auto attribute) {
        ds.Replace(attribute.GetAsDataElement());
    };
    gdcm::Attribute<0x0008, 0x0016> sop_class;
    sop_class.SetValue(gdcm::MediaStorage::GetMSString(gdcm::MediaStorage::CTImageStorage));
    put(sop_class);
    gdcm::Attribute<0x0020, 0x000e> series;
    series.SetValue(series_uid);
    put(series);
    gdcm::Attribute<0x0020, 0x000d> study;
    study.SetValue(study_uid);
    put(study);
    gdcm::Attribute<0x0008, 0x0060> modality;
    modality.SetValue(spec.modality);
    put(modality);
    gdcm::Attribute<0x0008, 0x103e> description;
    description.SetValue(spec.description);
    put(description);
    gdcm::Attribute<0x0020, 0x0013> number;
    number.SetValue(instance);
    put(number);
    gdcm::Attribute<0x0018, 0x0050> thickness;
    thickness.SetValue(spec.slice_step);
    put(thickness);
    writer.SetFileName(path.c_str());
    if (!writer.Write()) {
        throw std::runtime_error("GDCM cannot write " + path.string());
    }
}

// Writes the spec's series into `dir` in a shuffled order under shuffled names (and shuffled
// InstanceNumbers); returns the files indexed by slice. `positions`, when not empty, gives each
// slice's distance from position0 along the normal (default k · slice_step).
inline std::vector<std::filesystem::path> write_dicom_series(const std::filesystem::path& dir,
                                                             DicomSeriesSpec spec,
                                                             std::uint32_t seed = 1,
                                                             std::vector<double> positions = {}) {
    std::filesystem::create_directories(dir);
    gdcm::UIDGenerator uids;
    if (spec.series_uid.empty()) {
        spec.series_uid = uids.Generate();
    }
    const std::string study_uid = uids.Generate();
    std::mt19937 random(seed);
    std::vector<int> names(static_cast<std::size_t>(spec.slices));
    std::iota(names.begin(), names.end(), 0);
    std::shuffle(names.begin(), names.end(), random);
    std::vector<int> order = names;
    std::shuffle(order.begin(), order.end(), random);
    std::vector<std::filesystem::path> files(static_cast<std::size_t>(spec.slices));
    for (const int k : order) {
        const auto kk = static_cast<std::size_t>(k);
        const double along = positions.empty() ? k * spec.slice_step : positions[kk];
        files[kk] = dir / ("img" + std::to_string(seed) + "_" + std::to_string(names[kk] * 7 % 97) +
                           "_" + std::to_string(names[kk]) + ".dcm");
        write_dicom_slice(files[kk], spec, spec.series_uid, study_uid, k, along, names[kk] + 1);
    }
    return files;
}

}  // namespace pliant::test
