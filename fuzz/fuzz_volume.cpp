// libFuzzer harness: io::read_volume, what every command that takes a volume calls: the dispatch
// by extension and the resampling of oblique volumes onto an axis-aligned grid, for the file
// layouts the per-format harnesses do not cover. The first byte picks the layout; the rest is the
// first file, a NUL byte, then the second file:
//   0: in.nii.gz (gzip NIfTI-1 or -2; no second file)
//   1: in.hdr + in.img (NIfTI pair; the header's size is 540 bytes when its first four bytes say
//      540 (NIfTI-2), else 348; no NUL separator, headers are binary)
//   2: in.mhd + in.raw (MetaImage with a detached data file, `ElementDataFile = in.raw`)
//   3: in.nrrd (attached NRRD; the oblique ones are resampled here)
#include <algorithm>

#include "fuzz_input.hpp"
#include "pliant/io/volume_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) {
        return 0;
    }
    const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
    std::filesystem::path path;
    switch (data[0] % 4) {
        case 0:
            path = pliant::fuzz::write_input("in.nii.gz", rest);
            break;
        case 1: {
            const bool nifti2 =
                rest.size() >= 4 && rest.substr(0, 4) == std::string_view("\x1c\x02\0\0", 4);
            const std::size_t header_size = std::min<std::size_t>(rest.size(), nifti2 ? 540 : 348);
            pliant::fuzz::write_input("in.img", rest.substr(header_size));
            path = pliant::fuzz::write_input("in.hdr", rest.substr(0, header_size));
            break;
        }
        case 2: {
            const auto [header, raw] = pliant::fuzz::split_at_nul(rest);
            pliant::fuzz::write_input("in.raw", raw);
            path = pliant::fuzz::write_input("in.mhd", header);
            break;
        }
        default:
            path = pliant::fuzz::write_input("in.nrrd", rest);
            break;
    }
    pliant::io::ReadVolumeOptions options;
    options.max_bytes = pliant::fuzz::MAX_BYTES;
    pliant::fuzz::expect_result_or_error([&] { pliant::io::read_volume(path, options); });
    return 0;
}
