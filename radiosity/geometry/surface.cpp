// radiosity/geometry/surface.cpp - the five surface kinds of DESIGN.md section 5.
#include "radiosity/geometry/surface.h"

#include <algorithm>
#include <cmath>

#include "math/check.h"
#include "math/gauss_legendre.h"

namespace mbr {

namespace {

/// Orthonormal frame (e1, e2, e3) with e3 along `axis` and e1 the part of `e1` normal to it.
void make_frame(Vec3 axis, Vec3 e1, Vec3& f1, Vec3& f2, Vec3& f3) {
    f3 = normalize(axis);
    MBR_CHECK_MSG(length(f3) > 0, "zero axis");
    f1 = e1 - dot(e1, f3) * f3;
    if (length(f1) < 1e-12 * length(e1) || length(e1) == 0) {
        // Any direction normal to the axis will do.
        f1 = std::fabs(f3.x) < 0.9 ? cross(f3, Vec3{1, 0, 0}) : cross(f3, Vec3{0, 1, 0});
    }
    f1 = normalize(f1);
    f2 = cross(f3, f1);
}

Vec3 bilinear(const Vec3* p, double u, double v) {
    return (1 - u) * (1 - v) * p[0] + u * (1 - v) * p[1] + u * v * p[2] + (1 - u) * v * p[3];
}

}  // namespace

Surface Surface::planar_quad(Vec3 p00, Vec3 p10, Vec3 p11, Vec3 p01) {
    Surface s = bilinear_patch(p00, p10, p11, p01);
    s.kind_ = Kind::PlanarQuad;
    return s;
}

Surface Surface::bilinear_patch(Vec3 p00, Vec3 p10, Vec3 p11, Vec3 p01) {
    Surface s;
    s.kind_ = Kind::BilinearPatch;
    s.p_[0] = p00;
    s.p_[1] = p10;
    s.p_[2] = p11;
    s.p_[3] = p01;
    return s;
}

Surface Surface::cylinder(Vec3 base, Vec3 axis, Vec3 e1, double radius, double height, double phi0,
                          double phi1, bool inward) {
    MBR_CHECK(radius > 0 && height > 0 && phi1 != phi0);
    Surface s;
    s.kind_ = Kind::Cylinder;
    s.p_[0] = base;
    make_frame(axis, e1, s.e1_, s.e2_, s.e3_);
    s.r1_ = radius;
    s.r0_ = height;
    s.a0_ = phi0;
    s.a1_ = phi1;
    s.inward_ = inward;
    return s;
}

Surface Surface::sphere(Vec3 centre, Vec3 pole, Vec3 e1, double radius, double theta0,
                        double theta1, double phi0, double phi1, bool inward) {
    MBR_CHECK(radius > 0 && theta0 != theta1 && phi0 != phi1);
    Surface s;
    s.kind_ = Kind::Sphere;
    s.p_[0] = centre;
    make_frame(pole, e1, s.e1_, s.e2_, s.e3_);
    s.r1_ = radius;
    s.a0_ = theta0;
    s.a1_ = theta1;
    s.b0_ = phi0;
    s.b1_ = phi1;
    s.inward_ = inward;
    return s;
}

Surface Surface::disk(Vec3 centre, Vec3 normal, Vec3 e1, double r0, double r1, double phi0,
                      double phi1) {
    MBR_CHECK(r0 >= 0 && r1 > r0 && phi1 != phi0);
    Surface s;
    s.kind_ = Kind::Disk;
    s.p_[0] = centre;
    make_frame(normal, e1, s.e1_, s.e2_, s.e3_);
    s.r0_ = r0;
    s.r1_ = r1;
    s.a0_ = phi0;
    s.a1_ = phi1;
    return s;
}

Surface Surface::reversed() const {
    Surface s = *this;
    switch (kind_) {
        case Kind::PlanarQuad:
        case Kind::BilinearPatch:
            std::swap(s.p_[1], s.p_[3]);  // (u, v) -> (v, u): x_u x x_v turns around
            break;
        case Kind::Cylinder:
        case Kind::Sphere:
            s.inward_ = !inward_;
            break;
        case Kind::Disk:
            // The normal, and e2 = normal x e1 with it; the angles negated, so that phi' = -phi
            // reaches the same points of the sector.
            s.e3_ = -e3_;
            s.e2_ = -e2_;
            s.a0_ = -a1_;
            s.a1_ = -a0_;
            break;
    }
    return s;
}

// The curved kinds map (u,v) to angles; `inward` mirrors one parameter so that x_u x x_v turns
// around: u for cylinders, v (the polar angle) for spheres, whose natural orientation is inward.

Vec3 Surface::point(double u, double v) const {
    switch (kind_) {
        case Kind::PlanarQuad:
        case Kind::BilinearPatch:
            return bilinear(p_, u, v);
        case Kind::Cylinder: {
            double uu = inward_ ? 1 - u : u;
            double phi = a0_ + uu * (a1_ - a0_);
            return p_[0] + r1_ * (std::cos(phi) * e1_ + std::sin(phi) * e2_) + v * r0_ * e3_;
        }
        case Kind::Sphere: {
            double vv = inward_ ? v : 1 - v;
            double theta = a0_ + vv * (a1_ - a0_);
            double phi = b0_ + u * (b1_ - b0_);
            double st = std::sin(theta);
            return p_[0] + r1_ * (st * std::cos(phi) * e1_ + st * std::sin(phi) * e2_ +
                                  std::cos(theta) * e3_);
        }
        case Kind::Disk: {
            double r = r0_ + u * (r1_ - r0_);
            double phi = a0_ + v * (a1_ - a0_);
            return p_[0] + r * (std::cos(phi) * e1_ + std::sin(phi) * e2_);
        }
    }
    return {};
}

void Surface::tangents(double u, double v, Vec3& x_u, Vec3& x_v) const {
    switch (kind_) {
        case Kind::PlanarQuad:
        case Kind::BilinearPatch:
            x_u = (1 - v) * (p_[1] - p_[0]) + v * (p_[2] - p_[3]);
            x_v = (1 - u) * (p_[3] - p_[0]) + u * (p_[2] - p_[1]);
            return;
        case Kind::Cylinder: {
            double sign = inward_ ? -1 : 1;
            double uu = inward_ ? 1 - u : u;
            double dphi = a1_ - a0_;
            double phi = a0_ + uu * dphi;
            x_u = sign * r1_ * dphi * (-std::sin(phi) * e1_ + std::cos(phi) * e2_);
            x_v = r0_ * e3_;
            return;
        }
        case Kind::Sphere: {
            double sign = inward_ ? 1 : -1;
            double vv = inward_ ? v : 1 - v;
            double dtheta = a1_ - a0_, dphi = b1_ - b0_;
            double theta = a0_ + vv * dtheta;
            double phi = b0_ + u * dphi;
            double st = std::sin(theta), ct = std::cos(theta);
            double sp = std::sin(phi), cp = std::cos(phi);
            x_u = r1_ * dphi * st * (-sp * e1_ + cp * e2_);
            x_v = sign * r1_ * dtheta * (ct * cp * e1_ + ct * sp * e2_ - st * e3_);
            return;
        }
        case Kind::Disk: {
            double dphi = a1_ - a0_;
            double r = r0_ + u * (r1_ - r0_);
            double phi = a0_ + v * dphi;
            x_u = (r1_ - r0_) * (std::cos(phi) * e1_ + std::sin(phi) * e2_);
            x_v = r * dphi * (-std::sin(phi) * e1_ + std::cos(phi) * e2_);
            return;
        }
    }
}

Vec3 Surface::normal(double u, double v) const {
    switch (kind_) {
        case Kind::Disk:
            return (a1_ > a0_) ? e3_ : -e3_;
        case Kind::Sphere: {
            // Radial direction: defined at the poles too, where x_u vanishes.
            Vec3 radial = normalize(point(u, v) - p_[0]);
            bool outward = !inward_;
            // Reversed angle ranges reverse the orientation of the parameterisation.
            if ((a1_ < a0_) != (b1_ < b0_)) outward = !outward;
            return outward ? radial : -radial;
        }
        default: {
            Vec3 x_u, x_v;
            tangents(u, v, x_u, x_v);
            Vec3 n = cross(x_u, x_v);
            double l = length(n);
            if (l > 1e-300) return n / l;
            // Degenerate point of a quad: the diagonals span the plane of the corners.
            return normalize(cross(p_[2] - p_[0], p_[3] - p_[1]));
        }
    }
}

double Surface::area_factor(double u, double v) const {
    Vec3 x_u, x_v;
    tangents(u, v, x_u, x_v);
    return length(cross(x_u, x_v));
}

bool Surface::bounded_kernel_at(const SurfacePoint& p) const {
    // DESIGN: within 1e-9 of the radius of the sphere or cylinder, the normal within 1e-6 of
    // the radial direction. On a cylinder of radius R, two points an angle phi and a height dz
    // apart see each other with cosines 2 R sin^2(phi / 2) / r each (concave side), so the
    // kernel is 4 R^2 sin^4(phi / 2) / (pi r^4) <= 1 / (4 pi R^2).
    Vec3 radial;
    if (kind_ == Kind::Sphere) {
        radial = p.position - p_[0];
    } else if (kind_ == Kind::Cylinder) {
        const Vec3 d = p.position - p_[0];
        radial = d - dot(d, e3_) * e3_;
    } else {
        return false;
    }
    const double r = length(radial);
    if (!(std::fabs(r - r1_) <= 1e-9 * r1_)) return false;
    const double facing = dot(p.normal, radial) / r;  // +1 outward, -1 inward
    return inward_ ? facing <= -1 + 1e-6 : facing >= 1 - 1e-6;
}

bool Surface::on_same_quadric(const Surface& other) const {
    if (kind_ != other.kind_ || inward_ != other.inward_) return false;
    if (kind_ != Kind::Sphere && kind_ != Kind::Cylinder) return false;
    const double tol = 1e-9 * r1_;
    if (!(std::fabs(r1_ - other.r1_) <= tol)) return false;
    const Vec3 d = other.p_[0] - p_[0];
    if (kind_ == Kind::Sphere) return length(d) <= tol;
    // One axis line: parallel axes, and the bases' offset along it.
    return length(cross(e3_, other.e3_)) <= 1e-9 && length(d - dot(d, e3_) * e3_) <= tol;
}

SurfacePoint Surface::evaluate(double u, double v) const {
    Vec3 x_u, x_v;
    tangents(u, v, x_u, x_v);
    SurfacePoint sp;
    sp.position = point(u, v);
    Vec3 n = cross(x_u, x_v);
    sp.area_factor = length(n);
    sp.normal = (kind_ == Kind::Disk || kind_ == Kind::Sphere || sp.area_factor <= 1e-300)
                    ? normal(u, v)
                    : n / sp.area_factor;
    return sp;
}

double Surface::area() const {
    switch (kind_) {
        case Kind::PlanarQuad:
            // A planar quad's area is half the cross product of its diagonals.
            return 0.5 * length(cross(p_[2] - p_[0], p_[3] - p_[1]));
        case Kind::BilinearPatch: {
            // No closed form in general: the 8 x 8 Gauss-Legendre rule on 8 x 8 cells (A is
            // smooth; this is accurate to rounding for any reasonable patch).
            const GaussLegendre rule = gauss_legendre(8);
            const int cells = 8;
            double sum = 0;
            for (int ci = 0; ci < cells; ++ci)
                for (int cj = 0; cj < cells; ++cj) {
                    const Rect r{double(ci) / cells, double(ci + 1) / cells, double(cj) / cells,
                                 double(cj + 1) / cells};
                    sum += integrate_2d([&](double u, double v) { return area_factor(u, v); }, r,
                                        rule);
                }
            return sum;
        }
        case Kind::Cylinder:
            return r1_ * std::fabs(a1_ - a0_) * r0_;
        case Kind::Sphere:
            return r1_ * r1_ * std::fabs(b1_ - b0_) * std::fabs(std::cos(a0_) - std::cos(a1_));
        case Kind::Disk:
            return 0.5 * std::fabs(a1_ - a0_) * (r1_ * r1_ - r0_ * r0_);
    }
    return 0;
}

Box3 Surface::bounds() const {
    Box3 box;
    switch (kind_) {
        case Kind::PlanarQuad:
        case Kind::BilinearPatch:
            // A bilinear patch lies in the convex hull of its corners.
            for (const Vec3& p : p_) box.extend(p);
            return box;
        case Kind::Cylinder: {
            // The whole circle's box, over both ends: simple and always containing.
            Vec3 r = {r1_ * std::sqrt(1 - e3_.x * e3_.x), r1_ * std::sqrt(1 - e3_.y * e3_.y),
                      r1_ * std::sqrt(1 - e3_.z * e3_.z)};
            box.extend(p_[0] - r);
            box.extend(p_[0] + r);
            box.extend(p_[0] + r0_ * e3_ - r);
            box.extend(p_[0] + r0_ * e3_ + r);
            return box;
        }
        case Kind::Sphere:
            box.extend(p_[0] - Vec3{r1_, r1_, r1_});
            box.extend(p_[0] + Vec3{r1_, r1_, r1_});
            return box;
        case Kind::Disk: {
            Vec3 r = {r1_ * std::sqrt(1 - e3_.x * e3_.x), r1_ * std::sqrt(1 - e3_.y * e3_.y),
                      r1_ * std::sqrt(1 - e3_.z * e3_.z)};
            box.extend(p_[0] - r);
            box.extend(p_[0] + r);
            return box;
        }
    }
    return box;
}

long Surface::facet_count(int resolution) const {
    MBR_CHECK(resolution >= 1);
    if (kind_ == Kind::PlanarQuad) return 1;
    // The same counts as tessellate() below.
    const bool angular_u = kind_ == Kind::Cylinder || kind_ == Kind::Sphere;
    const bool angular_v = kind_ == Kind::Sphere || kind_ == Kind::Disk;
    const bool straight_u = kind_ == Kind::Disk, straight_v = kind_ == Kind::Cylinder;
    const long n_u = straight_u ? 1 : (angular_u ? std::max(resolution, 3) : resolution);
    const long n_v = straight_v ? 1 : (angular_v ? std::max(resolution, 3) : resolution);
    return (kind_ == Kind::BilinearPatch ? 2 : 1) * n_u * n_v;
}

std::vector<Facet> Surface::tessellate(int resolution) const {
    MBR_CHECK(resolution >= 1);
    std::vector<Facet> facets;
    if (kind_ == Kind::PlanarQuad) {
        facets.push_back({{p_[0], p_[1], p_[2], p_[3]}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}});
        return facets;
    }
    // An angular direction gets at least three facets: with one or two, a whole turn collapses
    // to a line or a doubled flat strip (a whole cylinder at resolution 1 had no facets at all).
    const bool angular_u = kind_ == Kind::Cylinder || kind_ == Kind::Sphere;
    const bool angular_v = kind_ == Kind::Sphere || kind_ == Kind::Disk;
    // A straight direction (a cylinder's height, a disk's radius) needs one facet: the facets
    // are exact along it, and every extra one is a polygon more for every ray and shadow.
    const bool straight_u = kind_ == Kind::Disk, straight_v = kind_ == Kind::Cylinder;
    const int n_u = straight_u ? 1 : (angular_u ? std::max(resolution, 3) : resolution);
    const int n_v = straight_v ? 1 : (angular_v ? std::max(resolution, 3) : resolution);
    for (int i = 0; i < n_u; ++i)
        for (int j = 0; j < n_v; ++j) {
            Vec2 q[4] = {{double(i) / n_u, double(j) / n_v},
                         {double(i + 1) / n_u, double(j) / n_v},
                         {double(i + 1) / n_u, double(j + 1) / n_v},
                         {double(i) / n_u, double(j + 1) / n_v}};
            Vec3 x[4];
            for (int c = 0; c < 4; ++c) x[c] = point(q[c].x, q[c].y);
            if (kind_ == Kind::BilinearPatch) {
                // A cell of a hyperbolic paraboloid is not planar: two triangles.
                facets.push_back({{x[0], x[1], x[2]}, {q[0], q[1], q[2]}});
                facets.push_back({{x[0], x[2], x[3]}, {q[0], q[2], q[3]}});
                continue;
            }
            // Cylinder, sphere and disk cells are planar (rectangles, isosceles trapezoids,
            // annular sectors' chords). Cells that collapse at a pole or centre become triangles.
            Facet f;
            for (int c = 0; c < 4; ++c) {
                if (!f.vertices.empty() && length(x[c] - f.vertices.back()) <= 1e-12 * r1_)
                    continue;
                f.vertices.push_back(x[c]);
                f.uv.push_back(q[c]);
            }
            if (f.vertices.size() >= 2 &&
                length(f.vertices.back() - f.vertices.front()) <= 1e-12 * r1_) {
                f.vertices.pop_back();
                f.uv.pop_back();
            }
            if (f.vertices.size() >= 3) facets.push_back(std::move(f));
        }
    return facets;
}

}  // namespace mbr
