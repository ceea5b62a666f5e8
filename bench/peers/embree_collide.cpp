#include "peers/embree_collide.hpp"

#include <fmt/format.h>

#include "pliant/core/error.hpp"

#if PLIANT_HAS_EMBREE

#include <embree3/rtcore.h>
#include <sys/types.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <string>

#include "pliant/collision/incidence.hpp"
#include "pliant/core/timer.hpp"

namespace pliant::bench {
namespace {

// Per-thread counters for the collide callback: a thread keeps the slot it first drew, so slots
// are (nearly) uncontended and each lives on its own cache line.
constexpr std::size_t NUM_SLOTS = 64;

struct alignas(64) CountSlot {
    std::atomic<std::int64_t> pairs{0};
    std::atomic<std::int64_t> mirrored{0};
    std::atomic<std::int64_t> reported{0};
};

std::size_t thread_slot() {
    static std::atomic<std::size_t> next{0};
    thread_local const std::size_t slot = next.fetch_add(1, std::memory_order_relaxed) % NUM_SLOTS;
    return slot;
}

struct CollideContext {
    const AABB* boxes = nullptr;
    const geometry::Triangle* triangles = nullptr;
    bool count_mirrored = false;
    std::array<CountSlot, NUM_SLOTS> slots;
};

bool accept(const CollideContext& ctx, unsigned a, unsigned b) {
    return overlaps(ctx.boxes[a], ctx.boxes[b]) &&
           !collision::share_vertex(ctx.triangles[a], ctx.triangles[b]);
}

// rtcCollide reports (a, b) and (b, a) for every candidate: keeping a < b counts each once.
void collide_callback(void* user, RTCCollision* collisions, unsigned num_collisions) {
    auto& ctx = *static_cast<CollideContext*>(user);
    std::int64_t pairs = 0;
    std::int64_t mirrored = 0;
    for (unsigned k = 0; k < num_collisions; ++k) {
        const unsigned a = collisions[k].primID0;
        const unsigned b = collisions[k].primID1;
        if (a < b) {
            pairs += accept(ctx, a, b) ? 1 : 0;
        } else if (ctx.count_mirrored && a > b) {
            mirrored += accept(ctx, b, a) ? 1 : 0;
        }
    }
    CountSlot& slot = ctx.slots[thread_slot()];
    slot.pairs.fetch_add(pairs, std::memory_order_relaxed);
    slot.mirrored.fetch_add(mirrored, std::memory_order_relaxed);
    slot.reported.fetch_add(num_collisions, std::memory_order_relaxed);
}

// The boxes a scene's bounds callback reads (the geometry's user data).
struct SceneState {
    RTCScene scene = nullptr;
    RTCGeometry geometry = nullptr;
    const AABB* boxes = nullptr;
    std::size_t count = 0;

    void release() {
        if (geometry != nullptr) {
            rtcReleaseGeometry(geometry);
            geometry = nullptr;
        }
        if (scene != nullptr) {
            rtcReleaseScene(scene);
            scene = nullptr;
        }
        boxes = nullptr;
        count = 0;
    }
};

void bounds_callback(const RTCBoundsFunctionArguments* args) {
    const auto& state = *static_cast<const SceneState*>(args->geometryUserPtr);
    const AABB& box = state.boxes[args->primID];
    RTCBounds& out = *args->bounds_o;
    out.lower_x = box.lo.x;
    out.lower_y = box.lo.y;
    out.lower_z = box.lo.z;
    out.upper_x = box.hi.x;
    out.upper_y = box.hi.y;
    out.upper_z = box.hi.z;
}

}  // namespace

bool embree_available() {
    return true;
}

std::string embree_version() {
    return RTC_VERSION_STRING;
}

struct EmbreeSelfCollider::Impl {
    RTCDevice device = nullptr;
    std::string last_error;
    std::atomic<std::int64_t> memory{0};
    std::atomic<std::int64_t> peak_memory{0};
    SceneState built;
    SceneState refitted;

    ~Impl() {
        built.release();
        refitted.release();
        if (device != nullptr) {
            rtcReleaseDevice(device);
        }
    }

    static void on_error(void* user, RTCError code, const char* message) {
        static_cast<Impl*>(user)->last_error =
            fmt::format("{} (code {})", message != nullptr ? message : "", static_cast<int>(code));
    }

    static bool on_memory(void* user, ssize_t bytes, bool /*post*/) {
        auto& impl = *static_cast<Impl*>(user);
        const std::int64_t now = impl.memory.fetch_add(bytes, std::memory_order_relaxed) +
                                 static_cast<std::int64_t>(bytes);
        std::int64_t peak = impl.peak_memory.load(std::memory_order_relaxed);
        while (now > peak &&
               !impl.peak_memory.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
        }
        return true;
    }

    void check(const char* what) {
        const RTCError code = rtcGetDeviceError(device);
        if (code != RTC_ERROR_NONE) {
            throw InternalError(fmt::format("Embree: {} failed: {}", what, last_error));
        }
    }

    // Creates the scene and its user geometry over `boxes`, geometry quality `quality`.
    void create(SceneState& state, std::span<const AABB> boxes, RTCBuildQuality quality) {
        state.release();
        state.boxes = boxes.data();
        state.count = boxes.size();
        state.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(state.geometry, static_cast<unsigned>(boxes.size()));
        rtcSetGeometryUserData(state.geometry, &state);
        rtcSetGeometryBoundsFunction(state.geometry, bounds_callback, nullptr);
        rtcSetGeometryBuildQuality(state.geometry, quality);
        state.scene = rtcNewScene(device);
        rtcSetSceneFlags(state.scene, RTC_SCENE_FLAG_DYNAMIC);
        rtcSetSceneBuildQuality(state.scene, RTC_BUILD_QUALITY_LOW);
        rtcAttachGeometry(state.scene, state.geometry);
        check("creating the user geometry scene");
    }

    // Points the scene at `boxes` and commits it (a rebuild or a refit, by geometry quality).
    double commit(SceneState& state, std::span<const AABB> boxes) {
        state.boxes = boxes.data();
        const Stopwatch watch;
        rtcCommitGeometry(state.geometry);
        rtcCommitScene(state.scene);
        const double ms = watch.elapsed_ms();
        check("rtcCommitScene");
        return ms;
    }
};

EmbreeSelfCollider::EmbreeSelfCollider(int num_threads) : m_impl(std::make_unique<Impl>()) {
    if (num_threads < 1) {
        throw InvalidInput(
            fmt::format("EmbreeSelfCollider: num_threads ({}) must be >= 1", num_threads));
    }
    const std::string config = fmt::format("threads={}", num_threads);
    m_impl->device = rtcNewDevice(config.c_str());
    if (m_impl->device == nullptr) {
        throw InternalError(fmt::format("Embree: rtcNewDevice(\"{}\") failed (error code {})",
                                        config, static_cast<int>(rtcGetDeviceError(nullptr))));
    }
    rtcSetDeviceErrorFunction(m_impl->device, &Impl::on_error, m_impl.get());
    rtcSetDeviceMemoryMonitorFunction(m_impl->device, &Impl::on_memory, m_impl.get());
}

EmbreeSelfCollider::~EmbreeSelfCollider() = default;

double EmbreeSelfCollider::build(std::span<const AABB> boxes) {
    if (m_impl->built.scene == nullptr || m_impl->built.count != boxes.size()) {
        m_impl->create(m_impl->built, boxes, RTC_BUILD_QUALITY_LOW);
    }
    return m_impl->commit(m_impl->built, boxes);
}

double EmbreeSelfCollider::refit(std::span<const AABB> boxes) {
    if (m_impl->refitted.scene == nullptr || m_impl->refitted.count != boxes.size()) {
        m_impl->create(m_impl->refitted, boxes, RTC_BUILD_QUALITY_REFIT);
    }
    return m_impl->commit(m_impl->refitted, boxes);
}

EmbreeCollideResult EmbreeSelfCollider::collide(Scene scene,
                                                std::span<const geometry::Triangle> triangles,
                                                bool count_mirrored) const {
    const SceneState& state = scene == Scene::built ? m_impl->built : m_impl->refitted;
    if (state.scene == nullptr) {
        throw InvalidInput(fmt::format("EmbreeSelfCollider::collide: the {} scene is not built",
                                       scene == Scene::built ? "built" : "refitted"));
    }
    if (triangles.size() != state.count) {
        throw InvalidInput(fmt::format(
            "EmbreeSelfCollider::collide: triangles.size() ({}) != number of boxes ({})",
            triangles.size(), state.count));
    }
    auto ctx = std::make_unique<CollideContext>();
    ctx->boxes = state.boxes;
    ctx->triangles = triangles.data();
    ctx->count_mirrored = count_mirrored;
    const Stopwatch watch;
    rtcCollide(state.scene, state.scene, collide_callback, ctx.get());
    EmbreeCollideResult result;
    result.ms = watch.elapsed_ms();
    m_impl->check("rtcCollide");
    std::int64_t mirrored = 0;
    for (const CountSlot& slot : ctx->slots) {
        result.pairs += slot.pairs.load(std::memory_order_relaxed);
        mirrored += slot.mirrored.load(std::memory_order_relaxed);
        result.reported += slot.reported.load(std::memory_order_relaxed);
    }
    result.mirrored_pairs = count_mirrored ? mirrored : -1;
    return result;
}

std::int64_t EmbreeSelfCollider::memory_bytes() const {
    return m_impl->memory.load(std::memory_order_relaxed);
}

std::int64_t EmbreeSelfCollider::peak_memory_bytes() const {
    return m_impl->peak_memory.load(std::memory_order_relaxed);
}

}  // namespace pliant::bench

#else  // PLIANT_HAS_EMBREE

namespace pliant::bench {

bool embree_available() {
    return false;
}

std::string embree_version() {
    return {};
}

struct EmbreeSelfCollider::Impl {};

EmbreeSelfCollider::EmbreeSelfCollider(int /*num_threads*/) {
    throw Unsupported(
        "EmbreeSelfCollider: pliant was built without Embree 3 (install libembree-dev and "
        "reconfigure with PLIANT_WITH_EMBREE=ON)");
}

EmbreeSelfCollider::~EmbreeSelfCollider() = default;

double EmbreeSelfCollider::build(std::span<const AABB> /*boxes*/) {
    return 0.0;
}

double EmbreeSelfCollider::refit(std::span<const AABB> /*boxes*/) {
    return 0.0;
}

EmbreeCollideResult EmbreeSelfCollider::collide(Scene /*scene*/,
                                                std::span<const geometry::Triangle> /*triangles*/,
                                                bool /*count_mirrored*/) const {
    return {};
}

std::int64_t EmbreeSelfCollider::memory_bytes() const {
    return 0;
}

std::int64_t EmbreeSelfCollider::peak_memory_bytes() const {
    return 0;
}

}  // namespace pliant::bench

#endif  // PLIANT_HAS_EMBREE
