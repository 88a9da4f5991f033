// sysid: the command-line program. Dispatches to one verb per subcommand and
// holds the ONE error funnel (STYLE.md "Two error channels", DESIGN.md "Exit codes"):
//   0 success
//   1 usage error (CLI11 parse errors, options that contradict each other)
//   2 bad input data or model file (sysid::DataError, std::invalid_argument)
//   3 numerical failure (sysid::NumericalError) or an internal error
// No exception is ever logged and followed by exit 0.
#include <sysid/config.hpp>
#include <sysid/core/errors.hpp>

#include <algorithm>
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace {

int run_in_funnel(const sysid::cli::Verb& verb) {
  const std::string who = "sysid " + verb.command->get_name();
  try {
    verb.run();
    return 0;
  } catch (const CLI::Error& e) {  // a usage problem found after parsing
    std::cerr << who << ": usage error: " << e.what() << "\nRun '" << who << " --help' for the options.\n";
    return 1;
  } catch (const sysid::DataError& e) {
    std::cerr << who << ": error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << who << ": error: " << e.what() << "\n";
    return 2;
  } catch (const sysid::NumericalError& e) {
    std::cerr << who << ": numerical failure: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << who << ": internal error: " << e.what() << "\n";
    return 3;
  } catch (...) {
    std::cerr << who << ": internal error: unknown exception\n";
    return 3;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sysid " SYSID_VERSION_STRING
               ": system identification for vibration and motion engineers.\n"
               "Turns recorded input/output logs (CSV) into validated state-space models.",
               "sysid"};
  app.set_version_flag("--version", SYSID_VERSION_STRING, "print the version and exit");
  app.require_subcommand(1, 1);
  app.footer(
      "Run 'sysid <verb> --help' for the options of a verb.\n"
      "Exit codes: 0 success, 1 usage error, 2 bad input data or model file, 3 numerical failure.\n"
      "Example:\n"
      "  sysid excite --signal multisine --fs 1000 --band 1:200 --samples 20000 --out u.csv\n"
      "  sysid n4sid log.csv --inputs u --outputs y --split 0.7 --out model.json\n"
      "  sysid frf log.csv --inputs u --outputs y --nfft 4096 --out frf.csv --plot frf.svg");

  std::vector<sysid::cli::Verb> verbs;
  try {
    for (const sysid::cli::VerbRegistration registration : sysid::cli::verb_registrations())
      verbs.push_back(registration(app));
    // Every verb that writes files gets --force; without it an existing output is
    // refused before any work (claim_outputs in cli_common.hpp).
    for (const auto& verb : verbs)
      for (const char* output_option : {"--out", "--json", "--plot", "--curve"})
        if (verb.command->get_option_no_throw(output_option) != nullptr) {
          sysid::cli::add_force_flag(*verb.command);
          break;
        }
  } catch (const std::exception& e) {  // a bug in an option definition
    std::cerr << "sysid: internal error: " << e.what() << "\n";
    return 3;
  }

  // The verb is the first argument that is not an option (the top level has
  // only flags). An unknown one is a usage error even with --help, which CLI11
  // would otherwise answer with the top-level help and exit 0.
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg.starts_with("-")) continue;
    const bool known = std::any_of(verbs.begin(), verbs.end(), [&](const auto& verb) { return verb.command->check_name(arg); });
    if (!known) {
      std::string names;
      for (const auto& verb : verbs) names += (names.empty() ? "" : ", ") + verb.command->get_name();
      std::cerr << "sysid: usage error: unknown verb '" << arg << "'; the verbs are: " << names
                << "\nRun 'sysid --help' for what each does.\n";
      return 1;
    }
    break;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version arrive here too, with exit code 0; app.exit prints the
    // help (of the chosen verb), the version, or the parse error message.
    const int code = app.exit(e);
    return code == 0 ? 0 : 1;
  }
  for (const auto& verb : verbs)
    if (verb.command->parsed()) return run_in_funnel(verb);
  std::cerr << "sysid: internal error: no verb selected\n";
  return 3;
}
