// The OGC audit on the detection's pairs (detail/ogc_step.hpp, audit_ogc_window) against the
// full CCD fail-safe with its broad phase.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "pliant/cloth/detail/ogc_step.hpp"
#include "pliant/cloth/ogc_contact.hpp"
#include "pliant/cloth/self_collision.hpp"
#include "pliant/collision/intersecting_pairs.hpp"

namespace pliant::cloth {
namespace {

// Two triangles: vertex 3 of the upper one 1 mm above the lower one's interior. Contact radius
// 5 mm: query radius 10 mm, ball 2.5 mm.
struct Window {
    std::vector<geometry::Triangle> triangles{{0, 1, 2}, {3, 4, 5}};
    std::vector<Vec3d> x{{0.0, 0.0, 0.0},     {0.1, 0.0, 0.0},   {0.0, 0.1, 0.0},
                         {0.02, 0.02, 0.001}, {0.2, 0.02, 0.05}, {0.02, 0.2, 0.05}};
    std::vector<double> inverse_masses = std::vector<double>(6, 1.0);
    OgcContact contact{triangles, x.size(), OgcOptions{}, 0.005, 100.0};

    Window() { contact.detect(x); }

    // The audit of the window from the detection to `end`: the positions and velocities after
    // it, the vertices it put back, and the window's counters.
    struct Result {
        std::vector<Vec3d> x;
        std::vector<Vec3d> v;
        std::int64_t reverted;
        detail::OgcAuditWindow window;
    };
    Result audit(const std::vector<Vec3d>& end, bool use_pairs) {
        SelfCollision self_collision(triangles, x.size(), 0.005);
        Result r{end, std::vector<Vec3d>(x.size(), Vec3d{1.0, 2.0, 3.0}), 0, {}};
        std::int64_t num_free = 0;
        detail::begin_ogc_step(contact, x, inverse_masses, r.window, num_free);
        detail::audit_ogc_window(self_collision, contact, r.window, r.x, r.v, use_pairs);
        r.reverted = self_collision.stats().reverted_vertices;
        return r;
    }
};

TEST(OgcAudit, PairAuditPutsBackWhatTheFullAuditDoes) {
    Window w;
    ASSERT_GE(w.contact.num_pairs(), 1U);
    // Vertex 3 pushed through the lower triangle, beyond physics but within its ball (2 mm);
    // vertex 4 slides 1 mm, clear of everything.
    std::vector<Vec3d> end = w.x;
    end[3].z = -0.001;
    end[4].x += 0.001;
    ASSERT_TRUE(detail::ogc_pairs_cover_window(
        w.contact,
        [&] {
            detail::OgcAuditWindow window;
            window.start = w.x;
            window.detections = w.contact.detections();
            return window;
        }(),
        end));
    const Window::Result pairs = w.audit(end, true);
    const Window::Result full = w.audit(end, false);
    EXPECT_EQ(pairs.window.pair_audits, 1);
    EXPECT_EQ(pairs.window.full_audits, 0);
    EXPECT_EQ(full.window.full_audits, 1);
    // The same vertices put back, bitwise: the lower triangle and vertex 3, with zero velocity.
    EXPECT_EQ(pairs.reverted, full.reverted);
    EXPECT_EQ(pairs.reverted, 4);
    EXPECT_EQ(pairs.x, full.x);
    EXPECT_EQ(pairs.v, full.v);
    EXPECT_EQ(pairs.x[3], w.x[3]);
    EXPECT_EQ(pairs.v[3], (Vec3d{0.0, 0.0, 0.0}));
    EXPECT_EQ(pairs.x[4], end[4]);
    EXPECT_EQ(collision::count_intersecting_pairs(pairs.x, w.triangles), 0);
    // The next window starts where this one ended.
    EXPECT_EQ(pairs.window.start, pairs.x);
}

TEST(OgcAudit, VertexBeyondItsBoundTakesTheFullAudit) {
    Window w;
    std::vector<Vec3d> end = w.x;
    end[3].z = -0.001;
    end[5].z += 0.02;  // away from everything, but 20 mm: more than half the query radius
    const Window::Result pairs = w.audit(end, true);
    EXPECT_EQ(pairs.window.pair_audits, 0);
    EXPECT_EQ(pairs.window.full_audits, 1);
    EXPECT_EQ(pairs.x[3], w.x[3]);  // still put back
    EXPECT_EQ(collision::count_intersecting_pairs(pairs.x, w.triangles), 0);
    // Without a detection too; and a window without motion audits nothing.
    w.contact.invalidate();
    std::vector<Vec3d> near = w.x;
    near[4].x += 0.001;
    EXPECT_EQ(w.audit(near, true).window.full_audits, 1);
    const Window::Result still = w.audit(w.x, true);
    EXPECT_EQ(still.window.full_audits + still.window.pair_audits, 0);
}

// The sheet carried 10 cm along x by the frame shift within the window, vertex 3 pushed through
// the lower triangle: the pair audit puts the four back at their starts, off the moving frame,
// so the check fails on the changed motion and the full fail-safe runs on it as well.
TEST(OgcAudit, VertexPutBackOffTheMovingFrameTakesTheFullAuditToo) {
    Window w;
    const Vec3d carried{0.1, 0.0, 0.0};
    SelfCollision self_collision(w.triangles, w.x.size(), 0.005);
    detail::OgcAuditWindow window;
    std::int64_t num_free = 0;
    detail::begin_ogc_step(w.contact, w.x, w.inverse_masses, window, num_free);
    std::vector<Vec3d> end = w.x;
    for (Vec3d& p : end) {
        p += carried;
    }
    ASSERT_TRUE(w.contact.set_shift(end, w.inverse_masses));
    end[3].z = -0.001;
    std::vector<Vec3d> v(end.size(), Vec3d{1.0, 0.0, 0.0});
    EXPECT_TRUE(detail::audit_ogc_window(self_collision, w.contact, window, end, v));
    EXPECT_EQ(window.pair_audits, 1);
    EXPECT_EQ(window.full_audits, 1);
    EXPECT_EQ(end[3], w.x[3]);
    EXPECT_EQ(end[0], w.x[0]);
    EXPECT_EQ(collision::count_intersecting_pairs(end, w.triangles), 0);
}

}  // namespace
}  // namespace pliant::cloth
