#include "camera/sim/characters.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {
namespace {

Material plain(float albedo) {
  Material m;
  m.albedo = m.albedo2 = albedo;
  m.pattern = Pattern::plain;
  return m;
}

Material patterned(Pattern pattern, float albedo, float albedo2, float period_mm,
                   std::uint32_t print_seed = 0) {
  Material m;
  m.albedo = albedo;
  m.albedo2 = albedo2;
  m.pattern = pattern;
  m.period_mm = period_mm;
  m.print_seed = print_seed;
  return m;
}

struct Spec {
  const char* name;
  double height_mm, girth;
  bool female;
  Clothing clothing;
  Hair hair;
  bool hat;
  Material skin, top, bottom, hair_material, hat_material, shoes;
  bool test_only;
};

Character make(const Spec& s) {
  Character c;
  c.name = s.name;
  c.shape.height_mm = s.height_mm;
  c.shape.girth = s.girth;
  c.shape.female = s.female;
  c.clothing = s.clothing;
  c.hair = s.hair;
  c.hat = s.hat;
  c.skin = s.skin;
  c.top = s.top;
  c.bottom = s.bottom;
  c.hair_material = s.hair_material;
  c.hat_material = s.hat_material;
  c.shoes = s.shoes;
  c.test_only = s.test_only;
  return c;
}

// Albedos are linear reflectances: skin from 0.08 (dark) to 0.45 (pale), cloth from 0.03
// (black) to 0.8 (white). Contrasting second colours make texture edges, hence events.
std::vector<Character> build_cast() {
  using P = Pattern;
  using C = Clothing;
  using H = Hair;
  const Spec specs[] = {
      // Training characters.
      {"ana", 1620, 0.90, true, C::dress, H::long_hair, false, plain(0.35f),
       patterned(P::stripes, 0.70f, 0.15f, 50), plain(0.30f), plain(0.06f), plain(0.5f),
       plain(0.05f), false},
      {"ben", 1800, 1.00, false, C::tight, H::short_cut, false, plain(0.22f), plain(0.06f),
       plain(0.10f), plain(0.04f), plain(0.5f), plain(0.7f), false},
      {"carl", 1920, 1.25, false, C::long_coat, H::short_cut, true, plain(0.40f),
       patterned(P::checks, 0.45f, 0.12f, 80), plain(0.08f), plain(0.30f), plain(0.05f),
       plain(0.04f), false},
      {"dana", 1550, 1.10, true, C::skirt, H::long_hair, false, plain(0.12f),
       patterned(P::stripes, 0.80f, 0.30f, 30), patterned(P::print, 0.60f, 0.10f, 45, 11),
       plain(0.03f), plain(0.5f), plain(0.60f), false},
      {"eli", 1700, 0.85, false, C::loose_shirt, H::short_cut, false, plain(0.30f),
       patterned(P::stripes, 0.75f, 0.05f, 70), plain(0.35f), plain(0.55f), plain(0.5f),
       plain(0.08f), false},
      {"fay", 1750, 0.80, true, C::long_coat, H::long_hair, true, plain(0.42f), plain(0.75f),
       plain(0.05f), plain(0.65f), plain(0.04f), plain(0.05f), false},
      {"gus", 1500, 1.40, false, C::loose_shirt, H::bald, true, plain(0.18f),
       patterned(P::print, 0.20f, 0.70f, 90, 23), plain(0.15f), plain(0.05f),
       patterned(P::stripes, 0.6f, 0.1f, 20), plain(0.3f), false},
      {"hana", 1680, 1.30, true, C::tight, H::short_cut, false, plain(0.28f),
       patterned(P::checks, 0.65f, 0.08f, 40), patterned(P::checks, 0.08f, 0.65f, 40),
       plain(0.02f), plain(0.5f), plain(0.50f), false},
      {"ivan", 1860, 1.15, false, C::tight, H::bald, false, plain(0.08f),
       patterned(P::stripes, 0.55f, 0.10f, 110), plain(0.70f), plain(0.02f), plain(0.5f),
       plain(0.06f), false},
      {"mia", 1900, 1.00, true, C::skirt, H::long_hair, false, plain(0.38f), plain(0.10f),
       patterned(P::stripes, 0.05f, 0.60f, 60), plain(0.45f), plain(0.5f), plain(0.03f),
       false},
      {"noah", 1600, 1.05, false, C::tight, H::short_cut, true, plain(0.25f),
       patterned(P::print, 0.50f, 0.05f, 60, 37), plain(0.45f), plain(0.10f), plain(0.70f),
       plain(0.10f), false},
      // Held out: a dress with a print and a hat, a striped long coat with long hair, a
      // checked loose shirt on a short wide body.
      {"jade", 1580, 1.00, true, C::dress, H::short_cut, true, plain(0.15f),
       patterned(P::print, 0.75f, 0.20f, 35, 41), plain(0.15f), plain(0.04f),
       plain(0.80f), plain(0.8f), true},
      {"kurt", 1950, 0.95, false, C::long_coat, H::long_hair, false, plain(0.33f),
       patterned(P::stripes, 0.10f, 0.50f, 45), plain(0.55f), plain(0.20f), plain(0.5f),
       plain(0.15f), true},
      {"lena", 1720, 1.20, true, C::loose_shirt, H::long_hair, false, plain(0.45f),
       patterned(P::checks, 0.85f, 0.25f, 55), plain(0.04f), plain(0.70f), plain(0.5f),
       plain(0.25f), true},
  };
  std::vector<Character> cast;
  for (const Spec& s : specs) {
    cast.push_back(make(s));
    const std::string& n = cast.back().name;
    cast.back().stripes_along = n == "eli" || n == "ivan" || n == "kurt";
  }
  return cast;
}

}  // namespace

const std::vector<Character>& characters() {
  static const std::vector<Character> cast = build_cast();
  return cast;
}

const Character& character_by_name(const std::string& name) {
  for (const Character& c : characters())
    if (c.name == name) return c;
  std::string known;
  for (const Character& c : characters()) known += (known.empty() ? "" : ", ") + c.name;
  throw std::invalid_argument("unknown character '" + name + "' (known: " + known + ")");
}

namespace {

// A cloth: plain in 40% of draws, else stripes, checks or a print with a second shade at
// least 0.2 away (weaker contrast makes texture edges too faint to matter).
Material random_cloth(Rng& r) {
  Material m;
  m.albedo = float(r.uniform(0.03, 0.8));
  const double u = r.uniform();
  m.pattern = u < 0.4 ? Pattern::plain : u < 0.65 ? Pattern::stripes : u < 0.85 ? Pattern::checks : Pattern::print;
  m.albedo2 = m.albedo;
  if (m.pattern != Pattern::plain) {
    // The other shade 0.2-0.6 away, on whichever side has room.
    const double d = r.uniform(0.2, 0.6) * (r.uniform() < 0.5 ? -1 : 1);
    double a2 = m.albedo + d;
    if (a2 < 0.02 || a2 > 0.85) a2 = m.albedo - d;
    m.albedo2 = float(std::clamp(a2, 0.02, 0.85));
    m.period_mm = float(r.uniform(20, 110));
    m.print_seed = std::uint32_t(r.bits() & 0xffff);
  }
  return m;
}

Material random_plain(Rng& r, double lo, double hi) {
  Material m;
  m.albedo = m.albedo2 = float(r.uniform(lo, hi));
  return m;
}

}  // namespace

std::string looks_name(std::uint64_t seed) {
  static const char* hex = "0123456789abcdef";
  std::string n = "r";
  for (int i = 4; i >= 0; --i) n += hex[(seed >> (4 * i)) & 15];
  return n;
}

Character random_looks(const Character& base, std::uint64_t seed) {
  Rng r(seed, 0x100c5);
  Character c = base;
  c.name = looks_name(seed);
  c.shape.female = r.uniform() < 0.5;
  c.shape.height_mm = r.uniform(1500, 1950);
  c.shape.girth = r.uniform(0.8, 1.4);
  c.clothing = Clothing(r.below(5));
  c.hair = Hair(r.below(3));
  c.hat = r.uniform() < 0.25;
  c.skin = random_plain(r, 0.08, 0.45);
  c.top = random_cloth(r);
  c.bottom = random_cloth(r);
  c.hair_material = random_plain(r, 0.02, 0.7);
  c.hat_material = random_cloth(r);
  c.shoes = random_plain(r, 0.03, 0.8);
  c.stripes_along = r.uniform() < 0.5;
  return c;
}

const char* clothing_name(Clothing clothing) {
  switch (clothing) {
    case Clothing::tight: return "tight";
    case Clothing::loose_shirt: return "loose_shirt";
    case Clothing::long_coat: return "long_coat";
    case Clothing::dress: return "dress";
    case Clothing::skirt: return "skirt";
  }
  return "unknown";
}

}  // namespace yelan::camera::sim
