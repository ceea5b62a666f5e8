// pliant volume info|series|convert|clean|generate: volume files (io/volume_io.hpp).
//
//   pliant volume info VOLUME [--series UID] [--max-memory MIB] [--json]
//       dims, voxel type, spacing, origin, direction, world box, bytes, and min / max / mean per
//       channel; for DICOM also the series read and the others in the folder. Oblique volumes
//       are shown as stored (not resampled).
//   pliant volume series DIR [--json]
//       the DICOM series in a folder (io/dicom.hpp): UID, modality, description, files, dims.
//   pliant volume convert IN OUT [--series UID] [--gzip] [--nifti2] [--max-memory MIB]
//       any readable format to any writable one (chosen by OUT's extension), voxels and
//       orientation unchanged (every writable format holds the direction).
//   pliant volume clean IN OUT --threshold T [--normalize max|range|none]
//       RGBA volumes: α' = 0 where 255·α < T, then alpha normalization (volume/clean.hpp gives the
//       exact formulas; the paper used T = 5, 20, 35).
//   pliant volume generate shepp-logan|sphere|rgba-test OUT [--dims N]
//       the generated volumes of volume/generate.hpp (Shepp–Logan: f32 over [−1, 1]³; sphere:
//       f32 value 1 of radius 0.8 in [−1, 1]³; rgba-test: the RGBA orientation object).
//
// Every read refuses declared sizes above --max-memory (MiB, default 16384) before allocating.
// Bad files: `pliant: error: …`, exit 1; bad options: exit 2. Outputs are written atomically.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "pliant/core/error.hpp"
#include "pliant/io/dicom.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/volume/clean.hpp"
#include "pliant/volume/generate.hpp"
#include "validators.hpp"

namespace pliant::cli {
namespace {

struct VolumeOptions {
    std::string input;
    std::string output;
    std::string series;
    std::string grid;
    double max_memory_mib = 16384.0;
    bool gzip = false;
    bool nifti2 = false;
    double threshold = 0.0;
    std::string normalize = "max";
    std::string kind;
    int dims = 128;
};

// Volume files are read as stored: an oblique volume keeps its direction (info shows it,
// convert and clean write it).
io::ReadVolumeOptions read_options(const VolumeOptions& options) {
    io::ReadVolumeOptions read;
    read.max_bytes = static_cast<std::size_t>(options.max_memory_mib * 1024.0 * 1024.0);
    read.orientation = io::Orientation::keep;
    read.series_uid = options.series;
    read.grid = options.grid;
    return read;
}

nlohmann::ordered_json series_json(const io::DicomSeriesInfo& info) {
    return {{"uid", info.uid},
            {"modality", info.modality},
            {"description", info.description},
            {"files", info.num_files},
            {"dims", {info.dims[0], info.dims[1], info.dims[2]}},
            {"first_file", info.first_file.string()}};
}

std::string series_text(const io::DicomSeriesInfo& info) {
    return fmt::format("{}  {:<4} {:>5} files  {}x{}x{}  {}", info.uid,
                       info.modality.empty() ? "?" : info.modality, info.num_files, info.dims[0],
                       info.dims[1], info.dims[2], info.description);
}

struct ChannelStats {
    double min = std::numeric_limits<double>::infinity();
    double max = -std::numeric_limits<double>::infinity();
    double sum = 0.0;
};

// Min, max and mean of every channel (NaNs skipped).
template <volume::VoxelType T>
std::vector<ChannelStats> channel_stats(const volume::Volume& v) {
    const int channels = volume::channels(T);
    std::vector<ChannelStats> stats(static_cast<std::size_t>(channels));
    const auto values = v.values<T>();
    for (std::size_t i = 0; i < values.size(); ++i) {
        const auto x = static_cast<double>(values[i]);
        if (x != x) {
            continue;
        }
        ChannelStats& s = stats[i % static_cast<std::size_t>(channels)];
        s.min = std::min(s.min, x);
        s.max = std::max(s.max, x);
        s.sum += x;
    }
    return stats;
}

std::vector<ChannelStats> channel_stats(const volume::Volume& v) {
    switch (v.type()) {
        case volume::VoxelType::u8:
            return channel_stats<volume::VoxelType::u8>(v);
        case volume::VoxelType::i16:
            return channel_stats<volume::VoxelType::i16>(v);
        case volume::VoxelType::u16:
            return channel_stats<volume::VoxelType::u16>(v);
        case volume::VoxelType::f32:
            return channel_stats<volume::VoxelType::f32>(v);
        case volume::VoxelType::rgba8:
            return channel_stats<volume::VoxelType::rgba8>(v);
        case volume::VoxelType::rgba32f:
            return channel_stats<volume::VoxelType::rgba32f>(v);
    }
    return {};
}

void run_info(const VolumeOptions& options, const GlobalOptions& global) {
    const volume::Volume v = io::read_volume(options.input, read_options(options));
    const std::vector<ChannelStats> stats = channel_stats(v);
    const AABBd box = v.world_bounds();
    const volume::Direction& d = v.direction();
    const io::VolumeFormat format = io::volume_format(options.input);
    nlohmann::ordered_json channels = nlohmann::ordered_json::array();
    for (const ChannelStats& s : stats) {
        channels.push_back({{"min", s.min},
                            {"max", s.max},
                            {"mean", s.sum / static_cast<double>(v.num_voxels())}});
    }
    nlohmann::ordered_json json = {
        {"file", options.input},
        {"format", io::name(format)},
        {"dims", {v.dims()[0], v.dims()[1], v.dims()[2]}},
        {"type", volume::name(v.type())},
        {"spacing", {v.spacing().x, v.spacing().y, v.spacing().z}},
        {"origin", {v.origin().x, v.origin().y, v.origin().z}},
        {"direction",
         {{d[0].x, d[0].y, d[0].z}, {d[1].x, d[1].y, d[1].z}, {d[2].x, d[2].y, d[2].z}}},
        {"axis_aligned", v.is_axis_aligned()},
        {"bounds", {{box.lo.x, box.lo.y, box.lo.z}, {box.hi.x, box.hi.y, box.hi.z}}},
        {"voxels", v.num_voxels()},
        {"bytes", v.size_bytes()},
        {"channels", channels}};
    std::vector<io::DicomSeriesInfo> series;
    std::string series_uid;
    if (format == io::VolumeFormat::dicom) {
        series = io::list_dicom_series(options.input);
        series_uid = io::chosen_dicom_series(options.input, options.series);
        json["series_uid"] = series_uid;
        nlohmann::ordered_json list = nlohmann::ordered_json::array();
        for (const io::DicomSeriesInfo& info : series) {
            list.push_back(series_json(info));
        }
        json["series"] = list;
    }
    if (global.json) {
        std::fputs((json.dump(2) + "\n").c_str(), stdout);
        return;
    }
    std::string text = fmt::format("{} ({})\n", options.input, io::name(format));
    text += fmt::format("  dims      {} x {} x {} {} voxels ({:.1f} MiB)\n", v.dims()[0],
                        v.dims()[1], v.dims()[2], volume::name(v.type()),
                        static_cast<double>(v.size_bytes()) / (1024.0 * 1024.0));
    text += fmt::format("  spacing   {} {} {}\n", v.spacing().x, v.spacing().y, v.spacing().z);
    if (!v.is_axis_aligned()) {
        text += fmt::format(
            "  direction i ({:.6f}, {:.6f}, {:.6f})  j ({:.6f}, {:.6f}, {:.6f})  k ({:.6f}, "
            "{:.6f}, {:.6f}): oblique (render, deform, dataset and view resample it to an "
            "axis-aligned grid)\n",
            d[0].x, d[0].y, d[0].z, d[1].x, d[1].y, d[1].z, d[2].x, d[2].y, d[2].z);
        text += fmt::format("  origin    {} {} {} (corner of voxel 0)\n", v.origin().x,
                            v.origin().y, v.origin().z);
    }
    text += fmt::format("  box       [{}, {}, {}] .. [{}, {}, {}]\n", box.lo.x, box.lo.y, box.lo.z,
                        box.hi.x, box.hi.y, box.hi.z);
    const char* names[4] = {"r", "g", "b", "a"};
    for (std::size_t c = 0; c < stats.size(); ++c) {
        text += fmt::format("  {:<9} min {:.6g}  max {:.6g}  mean {:.6g}\n",
                            stats.size() == 1 ? "values" : names[c], stats[c].min, stats[c].max,
                            stats[c].sum / static_cast<double>(v.num_voxels()));
    }
    for (const io::DicomSeriesInfo& info : series) {
        text += fmt::format("  {} {}\n", info.uid == series_uid ? "series *" : "series  ",
                            series_text(info));
    }
    std::fputs(text.c_str(), stdout);
}

void run_series(const VolumeOptions& options, const GlobalOptions& global) {
    const std::vector<io::DicomSeriesInfo> series = io::list_dicom_series(options.input);
    if (global.json) {
        nlohmann::ordered_json list = nlohmann::ordered_json::array();
        for (const io::DicomSeriesInfo& info : series) {
            list.push_back(series_json(info));
        }
        const nlohmann::ordered_json json = {{"folder", options.input}, {"series", list}};
        std::fputs((json.dump(2) + "\n").c_str(), stdout);
        return;
    }
    std::string text = fmt::format("{}: {} DICOM series (largest first: read by default)\n",
                                   options.input, series.size());
    for (const io::DicomSeriesInfo& info : series) {
        text += "  " + series_text(info) + "\n";
    }
    std::fputs(text.c_str(), stdout);
}

void run_convert(const VolumeOptions& options) {
    const volume::Volume v = io::read_volume(options.input, read_options(options));
    io::WriteVolumeOptions write;
    write.gzip = options.gzip;
    write.nifti2 = options.nifti2;
    io::write_volume(options.output, v, write);
    std::printf("%s -> %s (%lld x %lld x %lld %s)\n", options.input.c_str(), options.output.c_str(),
                static_cast<long long>(v.dims()[0]), static_cast<long long>(v.dims()[1]),
                static_cast<long long>(v.dims()[2]), std::string(volume::name(v.type())).c_str());
}

void run_clean(const VolumeOptions& options) {
    volume::Volume v = io::read_volume(options.input, read_options(options));
    volume::CleanOptions clean;
    clean.threshold_255 = options.threshold;
    clean.normalization = options.normalize == "max" ? volume::AlphaNormalization::max
                          : options.normalize == "range"
                              ? volume::AlphaNormalization::threshold_range
                              : volume::AlphaNormalization::none;
    volume::clean(v, clean);
    io::WriteVolumeOptions write;
    write.gzip = options.gzip;
    io::write_volume(options.output, v, write);
    std::printf("%s -> %s (threshold %g, normalization %s)\n", options.input.c_str(),
                options.output.c_str(), options.threshold, options.normalize.c_str());
}

void run_generate(const VolumeOptions& options) {
    const volume::Dims dims{options.dims, options.dims, options.dims};
    volume::Volume v;
    if (options.kind == "shepp-logan") {
        v = volume::shepp_logan_3d(dims);
    } else if (options.kind == "sphere") {
        volume::SphereOptions sphere;
        const double spacing = 2.0 / options.dims;
        sphere.spacing = {spacing, spacing, spacing};
        sphere.origin = {-1.0, -1.0, -1.0};
        v = volume::uniform_sphere(dims, 0.8, 1.0f, sphere);
    } else {
        v = volume::rgba_test_object(dims);
    }
    io::WriteVolumeOptions write;
    write.gzip = options.gzip;
    io::write_volume(options.output, v, write);
    std::printf("%s: %s, %d^3 %s voxels\n", options.output.c_str(), options.kind.c_str(),
                options.dims, std::string(volume::name(v.type())).c_str());
}

void add_series_option(CLI::App* cmd, VolumeOptions& options) {
    cmd->add_option("--series", options.series,
                    "DICOM: the SeriesInstanceUID to read from a folder holding several (default: "
                    "the largest; pliant volume series DIR lists them)")
        ->type_name("UID");
    cmd->add_option("--grid", options.grid,
                    "OpenVDB: the float grid to read (default: \"density\", else the only one)")
        ->type_name("NAME");
}

void add_memory_option(CLI::App* cmd, VolumeOptions& options) {
    cmd->add_option("--max-memory", options.max_memory_mib,
                    "Refuse volumes whose voxels would need more than this (MiB; default 16384)")
        ->type_name("MIB")
        ->check(finite_in_range(1e-6, 1e9));
}

}  // namespace

void register_volume(CLI::App& app, const GlobalOptions& global) {
    auto options = std::make_shared<VolumeOptions>();
    CLI::App* cmd = app.add_subcommand(
        "volume",
        "Volume files: info, DICOM series, convert, clean (threshold, alpha normalization), "
        "generate");
    cmd->require_subcommand(1);

    CLI::App* info = cmd->add_subcommand("info", "Dims, type, spacing, box and value ranges");
    info->add_option("VOLUME", options->input,
                     "Volume file (.nrrd .nhdr .nii .nii.gz .hdr .mha .mhd .json .raw .raw.gz "
                     ".inv3 .vdb .dcm) or a folder of DICOM files")
        ->required();
    add_series_option(info, *options);
    add_memory_option(info, *options);
    info->callback([options, &global] { run_info(*options, global); });

    CLI::App* series =
        cmd->add_subcommand("series", "The DICOM series in a folder (UID, modality, files, dims)");
    series->add_option("DIR", options->input, "Folder of DICOM files (searched recursively)")
        ->required();
    series->callback([options, &global] { run_series(*options, global); });

    CLI::App* convert =
        cmd->add_subcommand("convert", "Convert between volume formats (by OUT's extension)");
    convert->add_option("IN", options->input, "Volume file or DICOM folder to read")->required();
    convert
        ->add_option("OUT", options->output,
                     "Volume file to write (.nrrd .nhdr .nii .nii.gz .mha .mhd .json)")
        ->required();
    add_series_option(convert, *options);
    convert->add_flag("--gzip", options->gzip,
                      "Compress the voxel data (NRRD and raw + JSON: gzip; MetaImage: zlib)");
    convert->add_flag("--nifti2", options->nifti2,
                      "Write NIfTI-2 (64-bit dims, double placement) instead of NIfTI-1");
    add_memory_option(convert, *options);
    convert->callback([options] { run_convert(*options); });

    CLI::App* clean = cmd->add_subcommand(
        "clean", "RGBA volumes: opacity threshold and alpha normalization (volume/clean.hpp)");
    clean->add_option("IN", options->input, "RGBA volume file to read")->required();
    clean->add_option("OUT", options->output, "Volume file to write")->required();
    clean
        ->add_option("--threshold", options->threshold,
                     "T on the 0-255 alpha scale: alpha = 0 where 255 alpha < T (0: none)")
        ->type_name("T")
        ->check(finite_in_range(0.0, 255.0));
    clean
        ->add_option("--normalize", options->normalize,
                     "max: alpha / max alpha; range: (alpha - T/255) / (1 - T/255); none")
        ->check(CLI::IsMember({"max", "range", "none"}));
    clean->add_flag("--gzip", options->gzip,
                    "Compress the voxel data (NRRD and raw + JSON: gzip; MetaImage: zlib)");
    add_memory_option(clean, *options);
    clean->callback([options] { run_clean(*options); });

    CLI::App* generate = cmd->add_subcommand("generate", "Write a generated volume");
    generate->add_option("KIND", options->kind, "shepp-logan, sphere or rgba-test")
        ->required()
        ->check(CLI::IsMember({"shepp-logan", "sphere", "rgba-test"}));
    generate->add_option("OUT", options->output, "Volume file to write")->required();
    generate->add_option("--dims", options->dims, "Voxels per axis")->check(CLI::Range(1, 2048));
    generate->add_flag("--gzip", options->gzip,
                       "Compress the voxel data (NRRD and raw + JSON: gzip; MetaImage: zlib)");
    generate->callback([options] { run_generate(*options); });

    cmd->footer("Global options --threads N and --json (see pliant --help) apply here too.");
}

}  // namespace pliant::cli
