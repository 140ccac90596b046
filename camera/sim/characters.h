// The simulator's cast: named characters with a body shape, an outfit and the materials it
// is made of. Names are short and lowercase because presets are built from them
// ("ana-05_04-front-high-static"). Some characters are held out from training, as the
// paper held out test subjects, so a network is scored on bodies and clothes it never saw.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "camera/sim/types.h"

namespace yelan::camera::sim {

// The main garment; it decides which surfaces carry the top and bottom materials and which
// loose cloth (with secondary motion) is added.
enum class Clothing : std::uint8_t {
  tight,        // top and trousers printed on the body surfaces
  loose_shirt,  // wider torso shell whose hem lags the body; trousers
  long_coat,    // coat with full sleeves and a skirt to below the knee; trousers
  dress,        // sleeveless top and skirt below the knee in one material; legs in `bottom`
  skirt,        // tight top, skirt above the knee in `bottom`, bare legs
};

enum class Hair : std::uint8_t {
  bald,
  short_cut,  // a cap over the skull
  long_hair,  // the cap and a spring-driven tail of round cones from the back of the head
};

struct Character {
  std::string name;
  BodyShape shape;
  Clothing clothing = Clothing::tight;
  Hair hair = Hair::short_cut;
  bool hat = false;
  // Pattern frames (origin/u/v) are set by the Dresser each sample; here they are unset.
  Material skin, top, bottom, hair_material, hat_material, shoes;
  // Stripes (and checks' first direction) run along the trunk, limbs and skirt instead of
  // around them: vertical stripes flicker under turns, hoops under bobbing and swinging.
  bool stripes_along = false;
  bool test_only = false;  // held out from training data
  // Scale of the front cues (brow band, chest print; body.cpp): 1 as drawn, 0 none, up to 3.
  double front_print = 1;
};

// Every character, training ones first; the list never changes at run time.
const std::vector<Character>& characters();

// Throws std::invalid_argument listing the known names when `name` is not one of them.
const Character& character_by_name(const std::string& name);

const char* clothing_name(Clothing clothing);

// The same named character with new looks drawn from `seed`: body (sex, 1500-1950 mm,
// girth 0.8-1.4), garment, hair, hat, skin and every material (plain or patterned, albedos
// and pattern sizes over the cast's whole range). A training set drawn this way shows the
// network a new person in every recording instead of the cast's nine, so it cannot learn
// poses by recognising outfits.
// Its name is looks_name(seed): "r" and 5 hex digits, no cast member's name.
Character random_looks(const Character& base, std::uint64_t seed);
std::string looks_name(std::uint64_t seed);

}  // namespace yelan::camera::sim
