#include "pliant/io/inv3.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/detail/volume_data.hpp"

namespace pliant::io {

namespace {

constexpr std::size_t BLOCK = 512;
constexpr std::uint64_t MAX_PLIST_BYTES = std::uint64_t{1} << 20;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& message) {
    throw IoError(fmt::format("{}: {}", path.string(), message));
}

struct GzClose {
    void operator()(gzFile_s* f) const { gzclose(f); }
};

// A gzip-compressed tar read sequentially with gzread.
class TarReader {
public:
    explicit TarReader(const std::filesystem::path& path) : m_path(path) {
        m_file.reset(gzopen(path.c_str(), "rb"));
        if (!m_file) {
            fail(path, "cannot open for reading");
        }
        gzbuffer(m_file.get(), 1 << 17);
    }

    struct Entry {
        std::string name;
        std::uint64_t size = 0;
        char type = '0';
    };

    // The next entry's header, or nullopt at the end of the archive.
    std::optional<Entry> next() {
        std::string long_name;
        while (true) {
            std::array<char, BLOCK> block{};
            const std::size_t n = read(block.data(), BLOCK);
            if (n == 0 && m_count == 0) {
                fail(m_path, "empty archive, expected a gzip-compressed tar (InVesalius .inv3)");
            }
            if (n < BLOCK) {
                fail(m_path, fmt::format("truncated tar archive, expected a {}-byte header "
                                         "block, got {} bytes",
                                         BLOCK, n));
            }
            ++m_count;
            if (std::all_of(block.begin(), block.end(), [](char c) { return c == 0; })) {
                return std::nullopt;
            }
            if (std::memcmp(block.data() + 257, "ustar", 5) != 0) {
                fail(m_path, "not a tar archive (no 'ustar' magic in a header block)");
            }
            Entry entry;
            entry.type = block[156];
            entry.size = octal(block.data() + 124, 12);
            std::string name(block.data(), strnlen(block.data(), 100));
            const std::string prefix(block.data() + 345, strnlen(block.data() + 345, 155));
            if (!prefix.empty()) {
                name = std::string(prefix).append("/").append(name);
            }
            if (entry.type == 'L') {  // GNU long name: the data is the next entry's name
                if (entry.size > 4096) {
                    fail(m_path, "tar long name longer than 4096 bytes");
                }
                long_name.assign(entry.size, '\0');
                read_exact(long_name.data(), entry.size);
                skip_padding(entry.size);
                long_name.resize(strnlen(long_name.data(), long_name.size()));
                continue;
            }
            entry.name = long_name.empty() ? name : long_name;
            return entry;
        }
    }

    void read_exact(void* out, std::uint64_t size) {
        auto* p = static_cast<char*>(out);
        std::uint64_t done = 0;
        while (done < size) {
            const std::size_t chunk =
                static_cast<std::size_t>(std::min<std::uint64_t>(size - done, 1u << 30));
            const std::size_t n = read(p + done, chunk);
            if (n == 0) {
                fail(m_path,
                     fmt::format("truncated tar entry, expected {} bytes, got {}", size, done));
            }
            done += n;
        }
    }

    void skip(std::uint64_t size) {
        std::vector<char> buffer(std::size_t{1} << 16);
        while (size > 0) {
            const auto chunk =
                static_cast<std::size_t>(std::min<std::uint64_t>(size, buffer.size()));
            read_exact(buffer.data(), chunk);
            size -= chunk;
        }
    }

    void skip_padding(std::uint64_t size) {
        const std::uint64_t rest = size % BLOCK;
        if (rest != 0) {
            skip(BLOCK - rest);
        }
    }

private:
    std::size_t read(char* out, std::size_t size) {
        std::size_t done = 0;
        while (done < size) {
            const int n = gzread(m_file.get(), out + done, static_cast<unsigned>(size - done));
            if (n < 0) {
                int code = 0;
                const char* message = gzerror(m_file.get(), &code);
                fail(m_path, fmt::format("corrupt gzip data: {}", message));
            }
            if (n == 0) {
                break;
            }
            done += static_cast<std::size_t>(n);
        }
        return done;
    }

    std::uint64_t octal(const char* field, std::size_t width) const {
        std::uint64_t value = 0;
        std::size_t i = 0;
        while (i < width && (field[i] == ' ' || field[i] == 0)) {
            ++i;
        }
        for (; i < width && field[i] >= '0' && field[i] <= '7'; ++i) {
            value = value * 8 + static_cast<std::uint64_t>(field[i] - '0');
            if (value > (std::uint64_t{1} << 40)) {
                fail(m_path, "tar entry size out of range");
            }
        }
        return value;
    }

    std::filesystem::path m_path;
    std::unique_ptr<gzFile_s, GzClose> m_file;
    std::size_t m_count = 0;
};

std::string base_name(const std::string& name) {
    const std::size_t slash = name.rfind('/');
    return slash == std::string::npos ? name : name.substr(slash + 1);
}

// --- A minimal XML property list: dict, array, string, integer, real, true, false. ---------------
struct PlistValue {
    enum class Kind { dict, array, string, integer, real, boolean } kind = Kind::string;
    std::string text;
    // A dict as parallel key and value lists (std::pair of an incomplete type is not allowed;
    // std::vector of one is, since C++17).
    std::vector<std::string> keys;
    std::vector<PlistValue> values;
    std::vector<PlistValue> array;

    const PlistValue* find(const std::string& key) const {
        for (std::size_t i = 0; i < keys.size(); ++i) {
            if (keys[i] == key) {
                return &values[i];
            }
        }
        return nullptr;
    }
};

class PlistParser {
public:
    PlistParser(std::filesystem::path path, std::string_view text)
        : m_path(std::move(path)), m_text(text) {}

    PlistValue parse_document() {
        const std::size_t start = m_text.find("<plist");
        if (start == std::string_view::npos) {
            fail(m_path, "main.plist is not an XML property list (no <plist>)");
        }
        m_pos = m_text.find('>', start);
        if (m_pos == std::string_view::npos) {
            fail(m_path, "main.plist: unterminated <plist> tag");
        }
        ++m_pos;
        return value(0);
    }

private:
    std::string tag() {
        skip_space();
        if (m_pos >= m_text.size() || m_text[m_pos] != '<') {
            fail(m_path, fmt::format("main.plist: expected a tag at byte {}", m_pos));
        }
        const std::size_t end = m_text.find('>', m_pos);
        if (end == std::string_view::npos) {
            fail(m_path, "main.plist: unterminated tag");
        }
        std::string t(m_text.substr(m_pos + 1, end - m_pos - 1));
        m_pos = end + 1;
        return t;
    }
    std::string text_until(const std::string& closing) {
        const std::size_t end = m_text.find(closing, m_pos);
        if (end == std::string_view::npos) {
            fail(m_path, fmt::format("main.plist: missing {}", closing));
        }
        std::string t(m_text.substr(m_pos, end - m_pos));
        m_pos = end + closing.size();
        return t;
    }
    void skip_space() {
        while (m_pos < m_text.size() && std::isspace(static_cast<unsigned char>(m_text[m_pos]))) {
            ++m_pos;
        }
    }
    PlistValue value(int depth) {
        if (depth > 32) {
            fail(m_path, "main.plist nested deeper than 32 levels");
        }
        const std::string t = tag();
        PlistValue v;
        if (t == "dict/" || t == "array/") {
            v.kind = t == "dict/" ? PlistValue::Kind::dict : PlistValue::Kind::array;
        } else if (t == "dict") {
            v.kind = PlistValue::Kind::dict;
            while (true) {
                const std::string k = tag();
                if (k == "/dict") {
                    break;
                }
                if (k != "key") {
                    fail(m_path, fmt::format("main.plist: expected <key> in a dict, got <{}>", k));
                }
                std::string key = text_until("</key>");
                PlistValue item = value(depth + 1);
                v.keys.push_back(std::move(key));
                v.values.push_back(std::move(item));
            }
        } else if (t == "array") {
            v.kind = PlistValue::Kind::array;
            while (true) {
                skip_space();
                if (m_text.substr(m_pos, 8) == "</array>") {
                    m_pos += 8;
                    break;
                }
                v.array.push_back(value(depth + 1));
            }
        } else if (t == "string" || t == "integer" || t == "real") {
            v.kind = t == "string"    ? PlistValue::Kind::string
                     : t == "integer" ? PlistValue::Kind::integer
                                      : PlistValue::Kind::real;
            v.text = text_until("</" + t + ">");
        } else if (t == "string/") {
            v.kind = PlistValue::Kind::string;
        } else if (t == "true/" || t == "false/") {
            v.kind = PlistValue::Kind::boolean;
            v.text = t == "true/" ? "true" : "false";
        } else {
            fail(m_path, fmt::format("main.plist: unexpected tag <{}>", t));
        }
        return v;
    }

    std::filesystem::path m_path;
    std::string_view m_text;
    std::size_t m_pos = 0;
};

struct Inv3Matrix {
    std::string filename;
    volume::Dims dims{};
    std::array<double, 3> spacing{};
};

Inv3Matrix parse_main_plist(const std::filesystem::path& path, std::string_view text) {
    const PlistValue root = PlistParser(path, text).parse_document();
    if (root.kind != PlistValue::Kind::dict) {
        fail(path, "main.plist: expected a dict at the top");
    }
    const PlistValue* matrix = root.find("matrix");
    if (matrix == nullptr || matrix->kind != PlistValue::Kind::dict) {
        fail(path, "main.plist has no 'matrix' dict");
    }
    const PlistValue* dtype = matrix->find("dtype");
    if (dtype == nullptr || dtype->text != "int16") {
        throw Unsupported(fmt::format("{}: main.plist matrix dtype {}, expected int16",
                                      path.string(),
                                      dtype != nullptr ? detail::quote(dtype->text) : "missing"));
    }
    const PlistValue* filename = matrix->find("filename");
    const PlistValue* shape = matrix->find("shape");
    if (filename == nullptr || filename->text.empty()) {
        fail(path, "main.plist matrix has no 'filename'");
    }
    if (shape == nullptr || shape->kind != PlistValue::Kind::array || shape->array.size() != 3) {
        fail(path, "main.plist matrix 'shape': expected 3 integers");
    }
    Inv3Matrix m;
    m.filename = filename->text;
    for (std::size_t i = 0; i < 3; ++i) {
        std::int64_t n = 0;
        if (detail::parse_integer(shape->array[i].text, n) != detail::ParseStatus::ok) {
            fail(path, fmt::format("main.plist matrix 'shape'[{}]: expected an integer, got {}", i,
                                   detail::quote(shape->array[i].text)));
        }
        m.dims[2 - i] = n;  // numpy C order (z, y, x) → x fastest
    }
    const PlistValue* spacing = root.find("spacing");
    if (spacing == nullptr || spacing->kind != PlistValue::Kind::array ||
        spacing->array.size() != 3) {
        fail(path, "main.plist 'spacing': expected 3 numbers");
    }
    for (std::size_t i = 0; i < 3; ++i) {
        double s = 0;
        if (detail::parse_real(spacing->array[i].text, s) != detail::ParseStatus::ok ||
            !std::isfinite(s) || s <= 0) {
            fail(path, fmt::format("main.plist 'spacing'[{}]: expected a finite number > 0, got {}",
                                   i, detail::quote(spacing->array[i].text)));
        }
        m.spacing[i] = s;
    }
    return m;
}

}  // namespace

volume::Volume read_inv3(const std::filesystem::path& path, std::size_t max_bytes) {
    if (detail::file_size(path) == 0) {
        fail(path, "empty file, expected a gzip-compressed tar (InVesalius .inv3)");
    }
    // Pass 1: main.plist (first in the files InVesalius writes).
    std::optional<Inv3Matrix> matrix;
    {
        TarReader tar(path);
        while (const auto entry = tar.next()) {
            if (base_name(entry->name) == "main.plist" && entry->type != '5') {
                if (entry->size > MAX_PLIST_BYTES) {
                    fail(path, fmt::format("main.plist larger than {} bytes", MAX_PLIST_BYTES));
                }
                std::string text(entry->size, '\0');
                tar.read_exact(text.data(), entry->size);
                matrix = parse_main_plist(path, text);
                break;
            }
            tar.skip(entry->size);
            tar.skip_padding(entry->size);
        }
    }
    if (!matrix) {
        fail(path, "no main.plist in the archive: not an InVesalius 3 project");
    }
    const std::size_t bytes =
        detail::check_declared_size(path, matrix->dims, volume::VoxelType::i16, max_bytes);
    // Pass 2: the matrix, straight into the volume once its size matches the plist.
    TarReader tar(path);
    while (const auto entry = tar.next()) {
        if (base_name(entry->name) != matrix->filename) {
            tar.skip(entry->size);
            tar.skip_padding(entry->size);
            continue;
        }
        if (entry->size != bytes) {
            fail(path, fmt::format("{}: main.plist declares shape {} of int16 ({} bytes), the "
                                   "archive entry has {} bytes",
                                   matrix->filename, detail::dims_text(matrix->dims), bytes,
                                   entry->size));
        }
        volume::Volume volume = volume::Volume::allocate(
            matrix->dims, volume::VoxelType::i16,
            {matrix->spacing[0], matrix->spacing[1], matrix->spacing[2]}, {0, 0, 0}, max_bytes);
        tar.read_exact(volume.bytes().data(), bytes);
        if constexpr (std::endian::native == std::endian::big) {
            detail::swap_channel_bytes(volume);
        }
        return volume;
    }
    fail(path, fmt::format("the archive has no '{}' (named by main.plist)", matrix->filename));
}

}  // namespace pliant::io
