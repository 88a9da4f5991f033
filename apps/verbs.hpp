#pragma once
// Registration of the sysid verbs. Each verb file defines one register_<verb>()
// that adds a CLI11 subcommand (options, help with an example) and returns the
// action main() runs after a successful parse, inside the one error funnel.
#include <sysid/core/io_data.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace sysid::cli {

/// What an identification verb found on one log, before printing or writing
/// anything: what `sysid family` needs from each member.
struct Identified {
  ModelFile file;                  ///< the model file the verb would write
  LogOptions log_options;          ///< how the verb read the log (columns, NaN policy ...)
  IoData estimation;               ///< the data the model was identified on (a copy)
  std::string report;              ///< what the verb prints on stdout
  std::vector<std::string> notes;  ///< "sysid VERB: note: ..." lines
  std::vector<std::string> warnings;
};

/// A registered verb: its subcommand and what to run when it was chosen.
/// run() reports failure only by throwing (see main.cpp for the exit codes).
/// Identification verbs also offer identify(log): the same work with the options
/// parsed for the verb, on another log, printing and writing nothing; it may be
/// called from several threads at once.
struct Verb {
  Verb() = default;
  Verb(CLI::App* command_, std::function<void()> run_, std::function<Identified(const std::string&)> identify_ = {})
      : command(command_), run(std::move(run_)), identify(std::move(identify_)) {}

  CLI::App* command = nullptr;
  std::function<void()> run;
  std::function<Identified(const std::string& log_path)> identify;
};

using VerbRegistration = Verb (*)(CLI::App&);

/// Every verb's registration, in the order `sysid --help` lists them.
const std::vector<VerbRegistration>& verb_registrations();

Verb register_n4sid(CLI::App& app);
Verb register_simulate(CLI::App& app);
Verb register_compare(CLI::App& app);
Verb register_show(CLI::App& app);
Verb register_excite(CLI::App& app);
Verb register_frf(CLI::App& app);
Verb register_psd(CLI::App& app);
Verb register_filter(CLI::App& app);
Verb register_resid(CLI::App& app);
Verb register_arx(CLI::App& app);
Verb register_ar(CLI::App& app);
Verb register_armax(CLI::App& app);
Verb register_arma(CLI::App& app);
Verb register_oe(CLI::App& app);
Verb register_assemble(CLI::App& app);
Verb register_hsv(CLI::App& app);
Verb register_reduce(CLI::App& app);
Verb register_lms(CLI::App& app);
Verb register_okid(CLI::App& app);
Verb register_era(CLI::App& app);
Verb register_diagnose(CLI::App& app);
Verb register_check(CLI::App& app);
Verb register_export(CLI::App& app);
Verb register_family(CLI::App& app);

}  // namespace sysid::cli
