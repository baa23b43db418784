// math/vec3.h - small value types shared by every library: Vec2, Vec3, Rgb, Rect, Box3.
// Plain aggregates with free functions (dot, cross, length, normalize), as in pbrt and
// geometry-central; each has operator<< so test failures print the offending values.
#pragma once

#include <algorithm>
#include <cmath>
#include <ostream>

namespace mbr {

constexpr double Pi = 3.14159265358979323846;
constexpr double InvPi = 1.0 / Pi;

/// A point or vector of the plane, used for parameters (u, v) and image coordinates.
struct Vec2 {
    double x = 0, y = 0;
};
inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline Vec2 operator*(Vec2 a, double s) { return {s * a.x, s * a.y}; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
/// z-component of the 3D cross product of (a, 0) and (b, 0).
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline std::ostream& operator<<(std::ostream& os, Vec2 a) {
    return os << '(' << a.x << ", " << a.y << ')';
}

/// A point, direction or normal of 3-space (deliberately one POD type, as in geometry-central).
struct Vec3 {
    double x = 0, y = 0, z = 0;
    double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline Vec3 operator*(Vec3 a, double s) { return {s * a.x, s * a.y, s * a.z}; }
inline Vec3 operator/(Vec3 a, double s) { return {a.x / s, a.y / s, a.z / s}; }
inline Vec3& operator+=(Vec3& a, Vec3 b) { a = a + b; return a; }
inline Vec3& operator-=(Vec3& a, Vec3 b) { a = a - b; return a; }
inline Vec3& operator*=(Vec3& a, double s) { a = s * a; return a; }
inline bool operator==(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
inline bool operator!=(Vec3 a, Vec3 b) { return !(a == b); }
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length_squared(Vec3 a) { return dot(a, a); }
inline double length(Vec3 a) { return std::sqrt(dot(a, a)); }
/// a / |a|; the zero vector stays zero rather than becoming NaN.
inline Vec3 normalize(Vec3 a) {
    double l = length(a);
    return l > 0 ? a / l : a;
}
inline Vec3 min(Vec3 a, Vec3 b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 max(Vec3 a, Vec3 b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline bool is_finite(Vec3 a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline std::ostream& operator<<(std::ostream& os, Vec3 a) {
    return os << '(' << a.x << ", " << a.y << ", " << a.z << ')';
}

/// Radiometric RGB triple (radiosity, reflectance, emission); kept apart from Vec3 on purpose.
struct Rgb {
    double r = 0, g = 0, b = 0;
    double operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    double& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
};
inline Rgb operator+(Rgb a, Rgb b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
inline Rgb operator-(Rgb a, Rgb b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
inline Rgb operator*(double s, Rgb a) { return {s * a.r, s * a.g, s * a.b}; }
inline Rgb operator*(Rgb a, double s) { return {s * a.r, s * a.g, s * a.b}; }
/// Channel-wise product (reflectance times irradiance).
inline Rgb operator*(Rgb a, Rgb b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
inline Rgb& operator+=(Rgb& a, Rgb b) { a = a + b; return a; }
inline Rgb& operator-=(Rgb& a, Rgb b) { a = a - b; return a; }
inline Rgb& operator*=(Rgb& a, double s) { a = s * a; return a; }
inline bool operator==(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
/// Largest absolute channel: the norm used by adaptive rules that integrate all three at once.
inline double max_abs(Rgb a) { return std::max({std::fabs(a.r), std::fabs(a.g), std::fabs(a.b)}); }
/// The sum of the three channels (a power or radiosity summed over colours).
inline double channel_sum(Rgb a) { return a.r + a.g + a.b; }
inline double max_abs(double a) { return std::fabs(a); }
inline double luminance(Rgb a) { return 0.2126 * a.r + 0.7152 * a.g + 0.0722 * a.b; }
inline std::ostream& operator<<(std::ostream& os, Rgb a) {
    return os << "rgb(" << a.r << ", " << a.g << ", " << a.b << ')';
}

/// Axis-aligned rectangle [x0, x1] x [y0, y1] of a parameter plane.
struct Rect {
    double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    double width() const { return x1 - x0; }
    double height() const { return y1 - y0; }
    double area() const { return width() * height(); }
    Vec2 centre() const { return {0.5 * (x0 + x1), 0.5 * (y0 + y1)}; }
};
inline std::ostream& operator<<(std::ostream& os, const Rect& r) {
    return os << '[' << r.x0 << ", " << r.x1 << "] x [" << r.y0 << ", " << r.y1 << ']';
}

/// Axis-aligned box of 3-space. An empty box has lo > hi.
struct Box3 {
    Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL};
    Vec3 hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    void extend(Vec3 p) { lo = min(lo, p); hi = max(hi, p); }
    void extend(const Box3& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
    Vec3 extent() const { return hi - lo; }
    Vec3 centre() const { return 0.5 * (lo + hi); }
};
/// Closed boxes overlap (touching counts).
inline bool overlaps(const Box3& a, const Box3& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
           a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}
inline std::ostream& operator<<(std::ostream& os, const Box3& b) {
    return os << "box[" << b.lo << " - " << b.hi << ']';
}

}  // namespace mbr
