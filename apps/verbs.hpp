#pragma once
// Registration of the sysid verbs. Each verb file defines one register_<verb>()
// that adds a CLI11 subcommand (options, help with an example) and returns the
// action main() runs after a successful parse, inside the one error funnel.
#include <CLI/CLI.hpp>
#include <functional>

namespace sysid::cli {

/// A registered verb: its subcommand and what to run when it was chosen.
/// run() reports failure only by throwing (see main.cpp for the exit codes).
struct Verb {
  CLI::App* command = nullptr;
  std::function<void()> run;
};

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

}  // namespace sysid::cli
