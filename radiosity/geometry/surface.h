// radiosity/geometry/surface.h - parametric surfaces on the rectilinear domain [0,1]^2 (paper
// section 2, eqs. (3)-(4); DESIGN.md section 5). Each gives the point x(u,v), the unit normal n =
// x_u x x_v / |x_u x x_v| (surfaces are one-sided: they emit and receive on the side n points to),
// the area factor A(u,v) = |x_u x x_v| of eq. (4), a bounding box, its area, and a tessellation
// into planar facets for ray casting.
#pragma once

#include <vector>

#include "math/vec3.h"

namespace mbr {

/// Everything the kernel (2)-(4) needs of one surface point.
struct SurfacePoint {
    Vec3 position;           // x(u,v)
    Vec3 normal;             // unit normal, the front side
    double area_factor = 0;  // A(u,v) = |x_u x x_v|, eq. (4)
};

/// One planar piece of a tessellation with the (u,v) of each corner (3 or 4 corners,
/// counter-clockwise seen from the front).
struct Facet {
    std::vector<Vec3> vertices;
    std::vector<Vec2> uv;
};

class Surface {
public:
    enum class Kind { PlanarQuad, BilinearPatch, Cylinder, Sphere, Disk };

    /// Bilinear map of four coplanar corners at (u,v) = (0,0), (1,0), (1,1), (0,1); rectangles
    /// and parallelograms are the common case. Its front is the side (p10-p00) x (p01-p00) faces.
    static Surface planar_quad(Vec3 p00, Vec3 p10, Vec3 p11, Vec3 p01);
    /// The same bilinear map without the planarity requirement (a hyperbolic paraboloid).
    static Surface bilinear_patch(Vec3 p00, Vec3 p10, Vec3 p11, Vec3 p01);
    /// Cylinder patch: x = base + r (cos phi e1 + sin phi e2) + v h axis, phi = phi0 + u (phi1 -
    /// phi0), e2 = axis x e1. Front outside unless inward (which mirrors u).
    static Surface cylinder(Vec3 base, Vec3 axis, Vec3 e1, double radius, double height,
                            double phi0, double phi1, bool inward = false);
    /// Sphere patch: polar angle theta in [theta0, theta1] from e3 = e1 x e2, azimuth phi in
    /// [phi0, phi1] from e1 in the plane of e1, e2 (e3 is the pole). Front outside unless inward.
    static Surface sphere(Vec3 centre, Vec3 pole, Vec3 e1, double radius, double theta0,
                          double theta1, double phi0, double phi1, bool inward = false);
    /// Disk (or annulus, or sector): x = centre + r (cos phi e1 + sin phi e2), r = r0 + u (r1 -
    /// r0), phi = phi0 + v (phi1 - phi0), e2 = normal x e1. Front is the side normal points to.
    static Surface disk(Vec3 centre, Vec3 normal, Vec3 e1, double r0, double r1, double phi0,
                        double phi1);

    Kind kind() const { return kind_; }
    /// The same surface facing the other way: the same points, the normal turned around (a
    /// quad's u and v swapped, a cylinder's or sphere's inward flag toggled, a disk's normal,
    /// second axis and angles negated).
    Surface reversed() const;
    /// x(u,v).
    Vec3 point(double u, double v) const;
    /// The partial derivatives x_u and x_v.
    void tangents(double u, double v, Vec3& x_u, Vec3& x_v) const;
    /// Unit normal x_u x x_v / |x_u x x_v| (the limit where A vanishes, as at a pole).
    Vec3 normal(double u, double v) const;
    /// A(u,v) = |x_u x x_v|, eq. (4).
    double area_factor(double u, double v) const;
    /// Point, normal and area factor at once.
    SurfacePoint evaluate(double u, double v) const;
    /// True when the surface lies in one plane (planar quads and disks).
    bool is_planar() const { return kind_ == Kind::PlanarQuad || kind_ == Kind::Disk; }
    /// True for a cylinder or sphere patch facing inward: its points can see each other.
    bool is_concave() const {
        return inward_ && (kind_ == Kind::Cylinder || kind_ == Kind::Sphere);
    }
    /// True when p lies on this patch's whole sphere or cylinder (any angle, any height) and faces
    /// the way the patch does: the kernel (3) from p to the patch is then bounded, by 1/(4 pi
    /// R^2) (on a sphere it is that constant on the concave side, zero on the convex one), so
    /// it has no peak near p that a quadrature's nodes could miss. False for other kinds.
    bool bounded_kernel_at(const SurfacePoint& p) const;
    /// True when both are patches of one whole sphere or cylinder (centre or axis and radius
    /// within 1e-9 of the radius) facing the same way.
    bool on_same_quadric(const Surface& other) const;
    /// Total area, the integral of A over [0,1]^2 (closed form where one exists).
    double area() const;
    /// A box containing the whole surface.
    Box3 bounds() const;
    /// Planar facets covering the surface; `resolution` facets along each curved parameter
    /// direction, at least 3 along an angle, one along a straight one (a cylinder's height, a
    /// disk's radius), where the facets are exact. Planar quads are always one facet; bilinear
    /// patches give two triangles per cell because their cells are not planar.
    std::vector<Facet> tessellate(int resolution) const;
    /// An upper bound of tessellate(resolution).size() (cells collapsed at a pole are dropped
    /// there), without building the facets: a cost estimate before the octree is built.
    long facet_count(int resolution) const;
    /// The four corners for quads, in (0,0), (1,0), (1,1), (0,1) order.
    const Vec3* corners() const { return p_; }

private:
    Kind kind_ = Kind::PlanarQuad;
    Vec3 p_[4];               // quad corners; for the others p_[0] is the centre/base
    Vec3 e1_, e2_, e3_;       // orthonormal frame (e3 = axis, pole or normal)
    double r0_ = 0, r1_ = 0;  // radius (r1_) or radii, height in r0_ for cylinders
    double a0_ = 0, a1_ = 0;  // first angle range (phi for cylinder/disk, theta for sphere)
    double b0_ = 0, b1_ = 0;  // second angle range (phi for sphere)
    bool inward_ = false;
};

}  // namespace mbr
