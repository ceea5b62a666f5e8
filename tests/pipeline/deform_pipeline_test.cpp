// The frame pipeline (pipeline/frame_pipeline.hpp): its order and slots against the sequential
// loop's, exceptions; and `run_deform` pipelined against sequential on 1 and 2 threads: every
// rendered frame's bytes, the output volume, the deformed mesh and the JSON's non-timing
// numbers, through both routes (exact, map).
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/io/volume_io.hpp"
#include "pliant/pipeline/deform_run.hpp"
#include "pliant/pipeline/frame_pipeline.hpp"
#include "pliant/volume/generate.hpp"
#include "support/deformed_phantom.hpp"
#include "support/test_files.hpp"

namespace pliant::pipeline {
namespace {

class FramePipelineTest : public ::testing::Test {
protected:
    void TearDown() override { set_num_threads(0); }
};

// What the pipeline promises: produce(f) after produce(f − 1) and consume(f − 2), consume(f)
// after produce(f) and consume(f − 1), slot f mod 2; every frame once.
TEST_F(FramePipelineTest, KeepsTheOrderTwoSlotsNeed) {
    for (const int threads : {1, 2}) {
        for (const bool pipelined : {false, true}) {
            set_num_threads(threads);
            std::mutex mutex;
            std::vector<int> produced, consumed;    // frames, in completion order
            std::array<int, 2> slot_frame{-1, -1};  // the frame each slot holds
            bool ok = true;
            const auto produce = [&](int frame, int slot) {
                const std::lock_guard lock(mutex);
                ok = ok && slot == (frame & 1);
                ok = ok && (produced.empty() || produced.back() == frame - 1);
                // The slot's previous frame (frame − 2) was consumed already.
                ok = ok && (frame - 2 < 3 || (!consumed.empty() && consumed.back() >= frame - 2));
                slot_frame[static_cast<std::size_t>(slot)] = frame;
                produced.push_back(frame);
            };
            const auto consume = [&](int frame, int slot) {
                const std::lock_guard lock(mutex);
                ok = ok && slot == (frame & 1) &&
                     slot_frame[static_cast<std::size_t>(slot)] == frame;
                ok = ok && (consumed.empty() || consumed.back() == frame - 1);
                consumed.push_back(frame);
            };
            run_frame_pipeline(3, 12, produce, consume, {.pipelined = pipelined});
            EXPECT_TRUE(ok) << threads << " threads, pipelined " << pipelined;
            ASSERT_EQ(produced.size(), 10u);
            ASSERT_EQ(consumed.size(), 10u);
            EXPECT_EQ(produced.front(), 3);
            EXPECT_EQ(consumed.back(), 12);
        }
    }
    set_num_threads(2);
    int calls = 0;
    run_frame_pipeline(
        5, 4, [&](int, int) { ++calls; }, [&](int, int) { ++calls; }, {});
    EXPECT_EQ(calls, 0);  // no frames
    EXPECT_THROW(run_frame_pipeline(
                     1, 2, [](int, int) {}, [](int, int) {}, {.producer_threads = -1}),
                 InvalidInput);
}

// An exception from either side ends the loop after the work in flight, and is rethrown.
TEST_F(FramePipelineTest, RethrowsAfterTheWorkInFlight) {
    set_num_threads(2);
    std::atomic<int> produced{0};
    EXPECT_THROW(run_frame_pipeline(
                     1, 10, [&](int, int) { ++produced; },
                     [&](int frame, int) {
                         if (frame == 4) {
                             throw IoError("disk full");
                         }
                     },
                     {}),
                 IoError);
    EXPECT_EQ(produced.load(), 5);  // frame 5 was in flight while frame 4 failed, and ended
    int consumed = 0;
    EXPECT_THROW(run_frame_pipeline(
                     1, 10,
                     [&](int frame, int) {
                         if (frame == 3) {
                             throw InvalidInput("bad step");
                         }
                     },
                     [&](int, int) { ++consumed; }, {}),
                 InvalidInput);
    EXPECT_EQ(consumed, 2);
}

struct RunResult {
    std::vector<std::vector<std::uint8_t>> frames;
    std::string volume, mesh;
    nlohmann::ordered_json json;
};

// A scalar source needs tf; an rgba8 one takes nullptr.
RunResult run(const volume::Volume& source, const volume::TransferFunction* tf, ResampleMode mode,
              bool pipelined, int threads, const io::test::TempDir& dir, int thin_levels = 2) {
    set_num_threads(threads);
    DeformRunOptions options;
    options.driver_name = "twist";
    options.driver = pbd::TwistDriver{.axis = pbd::Axis::z, .angle = 60.0, .ramp_time = 0.2};
    options.grid.cell_voxels = 3;
    options.body.stiffness = 0.8;
    options.body.substeps = 4;
    options.frames = 6;
    options.size = {48, 40};
    options.shading = true;
    options.resample = mode;
    options.pipelined = pipelined;
    options.checkpoint_every = 0;
    options.thin_levels = thin_levels;
    const std::string tag = std::string(name(mode)) + (pipelined ? "-p" : "-s") +
                            std::to_string(threads) + "-" + std::to_string(thin_levels);
    options.out = dir / (tag + ".nrrd");
    options.mesh_out = dir / (tag + ".vtu");
    RunResult result;
    options.frame_sink = [&](int frame, const render::Image& image) {
        EXPECT_EQ(frame, static_cast<int>(result.frames.size()) + 1);
        result.frames.push_back(image.pixels);
    };
    result.json = run_deform(source, tf, options);
    result.volume = io::test::read_bytes(options.out);
    result.mesh = io::test::read_bytes(options.mesh_out);
    return result;
}

TEST_F(FramePipelineTest, DeformRunsGiveTheSequentialBytes) {
    const io::test::TempDir dir;
    const volume::Volume source = volume::shepp_logan_3d({28, 26, 24});
    const volume::TransferFunction tf = volume::preset("mri-brain", source);
    for (const ResampleMode mode : {ResampleMode::exact, ResampleMode::map}) {
        const RunResult reference = run(source, &tf, mode, false, 1, dir);
        ASSERT_EQ(reference.frames.size(), 6u);
        EXPECT_FALSE(reference.json.at("pipelined").get<bool>());
        std::int64_t lit = 0;
        for (const std::uint8_t v : reference.frames.back()) {
            lit += v > 0 ? 1 : 0;
        }
        EXPECT_GT(lit, 100) << "the frames show the body";
        EXPECT_NE(reference.frames.front(), reference.frames.back()) << "the body moves";
        for (const auto& [pipelined, threads] :
             std::vector<std::pair<bool, int>>{{true, 1}, {true, 2}, {false, 2}}) {
            const RunResult r = run(source, &tf, mode, pipelined, threads, dir);
            const std::string what = std::string(name(mode)) + (pipelined ? " pipelined " : " ") +
                                     std::to_string(threads) + " threads";
            EXPECT_EQ(r.json.at("pipelined").get<bool>(), pipelined) << what;
            ASSERT_EQ(r.frames.size(), reference.frames.size()) << what;
            for (std::size_t f = 0; f < r.frames.size(); ++f) {
                EXPECT_TRUE(r.frames[f] == reference.frames[f]) << what << ", frame " << f + 1;
            }
            EXPECT_TRUE(r.volume == reference.volume) << what;
            EXPECT_TRUE(r.mesh == reference.mesh) << what;
            for (const char* key :
                 {"volume_ratio", "inverted_tets", "max_displacement", "mean_displacement",
                  "min_volume_ratio", "max_volume_ratio", "max_inverted_tets", "tets_skipped",
                  "voxels_written", "vertices", "tets"}) {
                EXPECT_EQ(r.json.at(key), reference.json.at(key)) << what << ": " << key;
            }
            EXPECT_GT(r.json.at("frame_period_ms").get<double>(), 0.0);
            EXPECT_GT(r.json.at("step_ms").get<double>(), 0.0);
            EXPECT_GT(r.json.at("render_ms").get<double>(), 0.0);
        }
    }
}

// thin_levels reaches the ray caster: an rgba8 source through the map renders other frames with
// the fixed step (0) than with the adaptive step's levels (1, 2), the output volume (the exact
// resample) is the same, and the JSON says which; out of [0, 2] the run refuses before writing.
TEST_F(FramePipelineTest, DeformRunsPassTheAdaptiveStepsLevels) {
    const io::test::TempDir dir;
    const volume::Volume source = test::rgba_phantom(28);
    std::vector<RunResult> runs;
    for (int levels = 0; levels <= 2; ++levels) {
        runs.push_back(run(source, nullptr, ResampleMode::map, true, 2, dir, levels));
        EXPECT_EQ(runs.back().json.at("thin_levels").get<int>(), levels);
        ASSERT_EQ(runs.back().frames.size(), 6u);
        EXPECT_TRUE(runs.back().volume == runs.front().volume);
    }
    EXPECT_NE(runs[0].frames.back(), runs[1].frames.back()) << "one level samples less";
    EXPECT_NE(runs[1].frames.back(), runs[2].frames.back()) << "the second level, shaded";
    DeformRunOptions bad;
    bad.driver = pbd::TwistDriver{};
    bad.out = dir / "bad.nrrd";
    bad.thin_levels = 3;
    EXPECT_THROW(run_deform(source, nullptr, bad), InvalidInput);
    EXPECT_FALSE(std::filesystem::exists(bad.out));
}

}  // namespace
}  // namespace pliant::pipeline
