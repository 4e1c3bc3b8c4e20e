// Small vector math: 3-vectors, RGB triples, rays, orthonormal frames.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lucent {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInf = INFINITY;
// Largest magnitude accepted for any input coordinate or value: squares and sums of such values
// stay finite in float, and Embree's rays stay valid (it rejects origins beyond about 1.8e18). A
// double, so that an input written as 1e15 is compared with 1e15 (the float 1e15f lies below it).
inline constexpr double kMaxInputMagnitude = 1e15;

struct Vec2 {
  float x = 0, y = 0;
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(Vec3 b) { x += b.x; y += b.y; z += b.z; return *this; }
  constexpr Vec3& operator-=(Vec3 b) { x -= b.x; y -= b.y; z -= b.z; return *this; }
  constexpr Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
};
constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
constexpr Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
constexpr Vec3 operator*(float s, Vec3 a) { return {a.x * s, a.y * s, a.z * s}; }
constexpr Vec3 operator/(Vec3 a, float s) { return {a.x / s, a.y / s, a.z / s}; }
constexpr bool operator==(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) { return a / length(a); }
inline Vec3 min(Vec3 a, Vec3 b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 max(Vec3 a, Vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
// x - x is 0 for finite x and NaN for infinities and NaN: one comparison instead of a branch per
// component (IEEE arithmetic is kept, -ffast-math is never used).
inline bool isFinite(Vec3 a) { return (a.x - a.x) + (a.y - a.y) + (a.z - a.z) == 0.0f; }
// The point with barycentric coordinates (1 - b1 - b2, b1, b2) in the triangle (v0, v1, v2): hit
// points, interpolated normals, samples on lights. One formula, so that every caller gets the same
// digits.
constexpr Vec3 barycentric(Vec3 v0, Vec3 v1, Vec3 v2, float b1, float b2) {
  return v0 * (1.0f - b1 - b2) + v1 * b1 + v2 * b2;
}
// Mirror reflection of w about n (both pointing away from the surface).
constexpr Vec3 reflect(Vec3 w, Vec3 n) { return 2.0f * dot(w, n) * n - w; }

// Linear RGB radiometric quantity.
struct Rgb {
  float r = 0, g = 0, b = 0;
  constexpr Rgb() = default;
  constexpr Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  constexpr explicit Rgb(float s) : r(s), g(s), b(s) {}
  constexpr float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
  constexpr float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
  constexpr Rgb& operator+=(Rgb o) { r += o.r; g += o.g; b += o.b; return *this; }
  constexpr Rgb& operator*=(Rgb o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
  constexpr Rgb& operator*=(float s) { r *= s; g *= s; b *= s; return *this; }
  constexpr bool isBlack() const { return r == 0 && g == 0 && b == 0; }
  constexpr float maxComponent() const { return std::max(r, std::max(g, b)); }
  constexpr float average() const { return (r + g + b) * (1.0f / 3.0f); }
  // Rec. 709 luminance, used for power-proportional light selection.
  constexpr float luminance() const { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }
};
constexpr Rgb operator+(Rgb a, Rgb b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
constexpr Rgb operator-(Rgb a, Rgb b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
constexpr Rgb operator*(Rgb a, Rgb b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
constexpr Rgb operator*(Rgb a, float s) { return {a.r * s, a.g * s, a.b * s}; }
constexpr Rgb operator*(float s, Rgb a) { return {a.r * s, a.g * s, a.b * s}; }
constexpr Rgb operator/(Rgb a, float s) { return {a.r / s, a.g / s, a.b / s}; }
constexpr bool operator==(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
inline bool isFinite(Rgb a) { return (a.r - a.r) + (a.g - a.g) + (a.b - a.b) == 0.0f; }

struct Ray {
  Vec3 origin;
  Vec3 direction;
  float tMin = 0.0f;
  float tMax = kInf;
};

// Orthonormal frame around a unit normal (Duff et al. 2017, branchless ONB).
struct Frame {
  Vec3 s, t, n;
  Frame() = default;
  explicit Frame(Vec3 normal) : n(normal) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    s = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
  }
  Vec3 toLocal(Vec3 v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 toWorld(Vec3 v) const { return s * v.x + t * v.y + n * v.z; }
};

// c ? a : b per component: a select the vectorizer takes in lane loops, where a branch between
// two vectors is not vectorized.
inline Vec3 select(bool c, Vec3 a, Vec3 b) { return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z}; }

// The distance below which a ray leaving p could meet p's own surface again through rounding: scaled
// to the coordinates' magnitude so that it works for scenes in millimetres and in metres alike.
inline float selfIntersectionScale(Vec3 p) {
  return 1e-4f * std::max(std::max(1.0f, std::abs(p.x)), std::max(std::abs(p.y), std::abs(p.z)));
}

// Offsets a ray origin off the surface along the geometric normal, by selfIntersectionScale.
inline Vec3 offsetOrigin(Vec3 p, Vec3 ng, Vec3 w) {
  const float scale = selfIntersectionScale(p);
  return p + ng * (dot(w, ng) > 0 ? scale : -scale);
}

struct Bounds3 {
  Vec3 lo{kInf, kInf, kInf};
  Vec3 hi{-kInf, -kInf, -kInf};
  void extend(Vec3 p) { lo = min(lo, p); hi = max(hi, p); }
  bool empty() const { return lo.x > hi.x; }
  Vec3 center() const { return (lo + hi) * 0.5f; }
  Vec3 extent() const { return hi - lo; }
};

}  // namespace lucent
