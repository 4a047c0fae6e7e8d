// Names of the step's stages (include/sphfem/core/profile.h).
#include "sphfem/core/profile.h"

namespace sphfem {

const char* stage_name(Stage s) {
  static const char* names[] = {"neighbors",   "proximity", "density",      "divergence", "forces",
                                "pressure",    "fem",       "body_contact", "collide",    "drift",
                                "contact_fix", "exchange",  "emit"};
  static_assert(sizeof names / sizeof names[0] == int(Stage::Count), "one name per stage");
  return names[int(s)];
}

}  // namespace sphfem
