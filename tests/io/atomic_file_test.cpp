#include "pliant/io/atomic_file.hpp"

#include <gtest/gtest.h>

#include <ostream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::expect_io_error;
using test::read_bytes;
using test::TempDir;
using test::write_bytes;

TEST(AtomicFile, WritesTheContent) {
    TempDir dir;
    write_file_atomically(dir / "a.txt", [](std::ostream& out) { out << "hello\n"; });
    EXPECT_EQ(read_bytes(dir / "a.txt"), "hello\n");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.txt"});
}

TEST(AtomicFile, ReplacesAnExistingFileAndKeepsBinaryBytes) {
    TempDir dir;
    write_bytes(dir / "a.bin", "a much longer previous content");
    const std::string binary("\0\r\n\x1a\xff", 5);
    write_file_atomically(dir / "a.bin", [&](std::ostream& out) { out << binary; });
    EXPECT_EQ(read_bytes(dir / "a.bin"), binary);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.bin"});
}

TEST(AtomicFile, MissingDirectoryThrowsAndLeavesNothing) {
    TempDir dir;
    const auto path = dir / "missing" / "a.txt";
    bool called = false;
    expect_io_error(
        [&] { write_file_atomically(path, [&](std::ostream&) { called = true; }); },
        {path.string(), "cannot create the temporary file", "No such file or directory"});
    EXPECT_FALSE(called);
    EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicFile, ThrowingWriterKeepsThePreviousFile) {
    TempDir dir;
    write_bytes(dir / "a.txt", "previous");
    EXPECT_THROW(write_file_atomically(dir / "a.txt",
                                       [](std::ostream& out) {
                                           out << "partial new content";
                                           out.flush();
                                           throw std::runtime_error("writer failed");
                                       }),
                 std::runtime_error);
    EXPECT_EQ(read_bytes(dir / "a.txt"), "previous");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.txt"});
}

TEST(AtomicFile, ThrowingWriterLeavesNoNewFile) {
    TempDir dir;
    EXPECT_THROW(
        write_file_atomically(dir / "new.txt", [](std::ostream&) { throw std::logic_error("no"); }),
        std::logic_error);
    EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicFile, FailedStreamThrowsIoError) {
    TempDir dir;
    write_bytes(dir / "a.txt", "previous");
    const auto path = dir / "a.txt";
    expect_io_error(
        [&] {
            write_file_atomically(path, [](std::ostream& out) {
                out << "data";
                out.setstate(std::ios::badbit);
            });
        },
        {path.string(), "writing the temporary file", "failed"});
    EXPECT_EQ(read_bytes(path), "previous");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.txt"});
}

TEST(AtomicFile, TargetIsADirectory) {
    TempDir dir;
    const auto target = dir / "sub";
    std::filesystem::create_directory(target);
    write_bytes(target / "inside.txt", "x");
    expect_io_error([&] { write_file_atomically(target, [](std::ostream& out) { out << "y"; }); },
                    {target.string(), "cannot replace the file"});
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"sub"});
    EXPECT_EQ(read_bytes(target / "inside.txt"), "x");
}

TEST(AtomicFile, PathWithoutFileName) {
    TempDir dir;
    const auto path = dir.path() / "";
    expect_io_error([&] { write_file_atomically(path, [](std::ostream&) {}); },
                    {"expected a file name"});
    EXPECT_TRUE(dir.entries().empty());
}

// Concurrent writers of one file: the file always holds one writer's complete content, and no
// temporary file is left behind.
TEST(AtomicFile, ConcurrentWritersLeaveOneCompleteContent) {
    TempDir dir;
    const auto path = dir / "shared.txt";
    const auto content_of = [](int writer) {
        return std::string(4096, static_cast<char>('a' + writer));
    };
    std::vector<std::thread> threads;
    threads.reserve(4);
    for (int writer = 0; writer < 4; ++writer) {
        threads.emplace_back([&, writer] {
            for (int i = 0; i < 20; ++i) {
                write_file_atomically(path, [&](std::ostream& out) { out << content_of(writer); });
            }
        });
    }
    for (std::thread& thread : threads) {
        thread.join();
    }
    const std::string content = read_bytes(path);
    ASSERT_EQ(content.size(), 4096u);
    EXPECT_EQ(content, content_of(content[0] - 'a'));
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"shared.txt"});
}

}  // namespace
}  // namespace pliant::io
