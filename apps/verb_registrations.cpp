// The list of the sysid verbs, in one place: main() registers them all, and
// `sysid family` registers its --method's verb on a private parser from it.
#include "verbs.hpp"

namespace sysid::cli {

const std::vector<VerbRegistration>& verb_registrations() {
  static const std::vector<VerbRegistration> list = {
      register_n4sid,  register_simulate, register_compare, register_show,     register_excite,   register_resid,
      register_frf,    register_psd,      register_filter,  register_arx,      register_ar,       register_armax,
      register_arma,   register_oe,       register_assemble, register_hsv,     register_reduce,   register_lms,
      register_okid,   register_era,      register_diagnose, register_check,   register_export,   register_family};
  return list;
}

}  // namespace sysid::cli
