// sysid family: one model per experiment of a manifest (any identification verb,
// with that verb's options), the modes followed across the members, a nominal
// model, the uncertainty bound and a weight that covers it (DESIGN.md "Model
// families over operating conditions").
#include <sysid/core/errors.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/median.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/family/mode_spread.hpp>
#include <sysid/family/model_family.hpp>
#include <sysid/io/family_file.hpp>
#include <sysid/io/family_manifest.hpp>
#include <sysid/validate/compare.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct FamilyArgs {
  std::vector<std::string> methods;  ///< --method: the first is the verb; a later one is that verb's own --method
  std::string band;
  std::string uncertainty = "multiplicative-output";
  int weight_order = ModelFamilyOptions{}.weight_order;
  std::string out;
  std::string plot;
};

/// The manifest and the method's options: everything family does not know itself,
/// in the order typed. The method's own parser reads them, with the manifest in
/// the place of its log.
struct MethodParser {
  CLI::App app{"sysid family member"};
  Verb verb;
};

std::unique_ptr<MethodParser> parse_method(const std::string& method, const std::vector<std::string>& rest) {
  auto parser = std::make_unique<MethodParser>();
  std::vector<std::string> identification;
  for (const VerbRegistration registration : verb_registrations()) {
    const Verb v = registration(parser->app);
    if (v.identify) identification.push_back(v.command->get_name());
    if (v.command->get_name() == method) parser->verb = v;
  }
  if (!parser->verb.identify)
    throw CLI::ValidationError("--method", "'" + method + "' is not an identification verb; one of: " + join(identification));
  for (const char* refused : {"--validate", "--stabilization", "--out", "--plot"})
    for (const std::string& arg : rest)
      if (arg == refused || arg.rfind(std::string(refused) + "=", 0) == 0)
        throw CLI::ValidationError(refused, std::string("is not a member option: ") +
                                                (std::string(refused) == "--validate"
                                                     ? "give each member's validation log in the manifest's 'validate' column"
                                                     : "family writes one file (--out) and one plot (--plot)"));
  std::vector<std::string> argv_text{"sysid", method};
  argv_text.insert(argv_text.end(), rest.begin(), rest.end());
  std::vector<const char*> argv;
  for (const std::string& a : argv_text) argv.push_back(a.c_str());
  try {
    parser->app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    throw CLI::ValidationError("--method " + method, std::string("the method's options: ") + e.what());
  }
  return parser;
}

/// What one member gave: its model file, fit and frequency-response error.
struct MemberOutcome {
  Identified identified;
  StateSpace analysis_model;  ///< the model the family compares (a time series: its unit-noise innovation form)
  Eigen::VectorXd fit_percent;
  FrequencyResponseError error;
};

MemberOutcome identify_member(const Verb& method, const FamilyManifestRow& row) {
  MemberOutcome out;
  out.identified = method.identify(row.log_path);
  const double Ts = out.identified.file.model.Ts;
  std::optional<IoData> validation;
  if (!row.validate_path.empty()) {
    validation = load_log(row.validate_path, out.identified.log_options).data;
    if (std::abs(validation->Ts - Ts) > 1e-6 * Ts)
      throw DataError(row.validate_path + ": sample time " + fmt(validation->Ts) + " s, the member's log has " + fmt(Ts) +
                      " s; a validation log must be sampled like its estimation log");
  }
  FamilyMemberEvidence evidence =
      family_member_evidence(out.identified.file, &out.identified.estimation, validation ? &*validation : nullptr);
  out.analysis_model = std::move(evidence.member.model);
  out.error = std::move(evidence.member.error);
  out.fit_percent = std::move(evidence.fit_percent);
  out.identified.estimation = IoData{};  // one log in memory per worker
  return out;
}

/// Every member on the cores (core/parallel_for.hpp; the method's own parallel
/// pieces then run on their member's thread). A member's failure names it.
std::vector<MemberOutcome> identify_members(const Verb& method, const FamilyManifest& manifest) {
  std::vector<MemberOutcome> outcomes(manifest.rows.size());
  parallel_for(manifest.rows.size(), [&](std::size_t k) {
    const FamilyManifestRow& row = manifest.rows[k];
    const std::string where = manifest.path + " line " + std::to_string(row.line) + " (member " + std::to_string(k) + ", " +
                              row.log + "): ";
    try {
      outcomes[k] = identify_member(method, row);
    } catch (const DataError& e) {
      throw DataError(where + e.what());
    } catch (const NumericalError& e) {
      throw NumericalError(where + e.what());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + e.what());
    }
  });
  return outcomes;
}

std::string members_table(const FamilyManifest& manifest, const std::vector<MemberOutcome>& members,
                          const std::vector<std::string>& outputs, bool validated, bool time_series) {
  std::ostringstream s;
  char buf[160];
  s << "members (" << members.size() << "; " << (time_series ? "one-step prediction fit" : "simulation fit") << " [%], x0 estimated, on "
    << (validated ? "each validate log" : "each own log") << "):\n";
  std::snprintf(buf, sizeof buf, "%4s", "#");
  s << buf;
  for (const Condition& c : manifest.conditions) {
    std::snprintf(buf, sizeof buf, "  %14s", c.name.c_str());
    s << buf;
  }
  std::snprintf(buf, sizeof buf, "  %6s", "order");
  s << buf;
  for (const std::string& y : outputs) {
    std::snprintf(buf, sizeof buf, "  %10s", ("fit " + y).c_str());
    s << buf;
  }
  s << "  log\n";
  for (std::size_t k = 0; k < members.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%4zu", k);
    s << buf;
    for (const Condition& c : manifest.conditions) {
      std::snprintf(buf, sizeof buf, "  %14s", condition_text(c.values[k]).c_str());
      s << buf;
    }
    std::snprintf(buf, sizeof buf, "  %6ld", static_cast<long>(members[k].identified.file.model.order()));
    s << buf;
    for (Eigen::Index i = 0; i < members[k].fit_percent.size(); ++i) {
      std::snprintf(buf, sizeof buf, "  %10.2f", members[k].fit_percent(i));
      s << buf;
    }
    s << "  " << manifest.rows[k].log << "\n";
  }
  return s.str();
}

std::string modes_table(const std::vector<TrackedMode>& modes, const std::vector<ModeSpread>& spreads, std::size_t members) {
  std::ostringstream s;
  if (modes.empty()) return "modes: none in the band\n";
  s << "modes followed across the members (in the band; frequency in Hz, damping ratio):\n";
  char buf[200];
  for (std::size_t j = 0; j < modes.size(); ++j) {
    const ModeSpread& sp = spreads[j];
    std::snprintf(buf, sizeof buf, "  mode %zu: %8.3f Hz [%.3f .. %.3f], damping %.4f [%.4f .. %.4f], in %d of %zu members\n",
                  j + 1, sp.freq_mean, sp.freq_min, sp.freq_max, sp.damping_mean, sp.damping_min, sp.damping_max, sp.present,
                  members);
    s << buf;
    // A mode most members lack is either physics of a few conditions or an
    // artefact of the identification (a noise mode at a too-high order): say so.
    if (2 * static_cast<std::size_t>(sp.present) < members)
      s << "    seen in fewer than half the members: a mode of some conditions only, or an identification artefact\n";
    for (const ConditionEffect& e : sp.effects) {
      if (e.numeric) {
        if (std::isnan(e.freq_slope)) continue;
        s << "    against " << e.condition << ": " << fmt(e.freq_slope, 4) << " +- " << fmt(e.freq_slope_se, 2)
          << " Hz per unit (" << fmt(100.0 * e.freq_slope / sp.freq_mean, 3) << " % of the mean), damping "
          << fmt(e.damping_slope, 3) << " +- " << fmt(e.damping_slope_se, 2) << " per unit\n";
      } else {
        s << "    by " << e.condition << ":";
        for (std::size_t k = 0; k < e.freq_by_label.size(); ++k)
          s << (k ? "," : "") << " " << e.freq_by_label[k].first << " "
            << (std::isnan(e.freq_by_label[k].second) ? std::string("absent") : fmt(e.freq_by_label[k].second, 5) + " Hz");
        s << "\n";
      }
    }
  }
  return s.str();
}

/// Bode magnitude of every member with the nominal; the bound, the spread and the
/// weight; each mode's frequency against each condition.
void plot_family(const std::string& path, const std::vector<MemberOutcome>& members, const ModelFamilyResult& family,
                 const FamilyManifest& manifest, int nominal, UncertaintyForm form) {
  PlotFigure fig;
  fig.title = "model family of " + manifest.path + " (" + std::to_string(members.size()) + " members)";
  const Eigen::VectorXd& f = family.frequency_hz;
  PlotPanel bode;
  bode.title = "largest singular value of every member; the nominal (member " + std::to_string(nominal) + ") in its own colour";
  bode.xlabel = "frequency [Hz]";
  bode.ylabel = "gain [dB]";
  bode.logx = true;
  for (std::size_t k = 0; k < members.size(); ++k) {
    PlotCurve c;
    c.x = f;
    c.y.resize(f.size());
    const auto frf = frequency_response(members[k].analysis_model, f);
    for (Eigen::Index i = 0; i < f.size(); ++i)
      c.y(i) = 20.0 * std::log10(Eigen::JacobiSVD<Eigen::MatrixXcd>(frf[static_cast<std::size_t>(i)]).singularValues()(0));
    c.color = static_cast<int>(k) == nominal ? 1 : 0;
    c.title = static_cast<int>(k) == nominal ? "nominal" : (k == 0 || (k == 1 && nominal == 0) ? "members" : "");
    bode.curves.push_back(std::move(c));
  }
  fig.panels.push_back(std::move(bode));
  if (family.bound) {
    PlotPanel b;
    b.title = "uncertainty (" + std::string(to_string(form)) + "): bound and weight";
    b.xlabel = "frequency [Hz]";
    b.ylabel = "magnitude";
    b.logx = b.logy = true;
    PlotCurve spread, bound, weight;
    spread.title = "members' deviation from the nominal (largest)";
    spread.x = f;
    spread.y = family.bound->spread;
    spread.color = 0;
    bound.title = "bound (with the estimation allowance)";
    bound.x = f;
    bound.y = family.bound->bound;
    bound.color = 1;
    b.curves.push_back(std::move(spread));
    b.curves.push_back(std::move(bound));
    if (family.weight) {
      weight.title = "|W|, order " + std::to_string(family.weight->weight.order());
      weight.x = f;
      weight.y = family.weight->magnitude;
      weight.color = 2;
      weight.dashed = true;
      b.curves.push_back(std::move(weight));
    }
    fig.panels.push_back(std::move(b));
  }
  for (const Condition& c : manifest.conditions) {
    PlotPanel p;
    p.title = "mode frequencies against " + c.name + (c.numeric() ? "" : " (labels in manifest order)");
    p.xlabel = c.name;
    p.ylabel = "frequency [Hz]";
    std::vector<std::string> labels;
    for (const ConditionValue& v : c.values)
      if (std::find(labels.begin(), labels.end(), condition_text(v)) == labels.end()) labels.push_back(condition_text(v));
    for (std::size_t j = 0; j < family.modes.modes.size(); ++j) {
      const TrackedMode& t = family.modes.modes[j];
      std::vector<double> x, y;
      for (Eigen::Index k = 0; k < t.freq_hz.size(); ++k) {
        if (std::isnan(t.freq_hz(k))) continue;
        const ConditionValue& v = c.values[static_cast<std::size_t>(k)];
        x.push_back(c.numeric() ? std::get<double>(v)
                                : static_cast<double>(std::find(labels.begin(), labels.end(), condition_text(v)) - labels.begin()));
        y.push_back(t.freq_hz(k));
      }
      PlotCurve curve;
      curve.title = "mode " + std::to_string(j + 1);
      curve.style = "points";
      curve.x = Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
      curve.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
      p.curves.push_back(std::move(curve));
    }
    if (!c.numeric()) p.xlabel = c.name + ": " + join(labels, ", ") + " = 0.." + std::to_string(labels.size() - 1);
    fig.panels.push_back(std::move(p));
  }
  fig.height_per_row = 330;
  write_plot(fig, path, "family");
}

/// "0-3, 7": member indices as ranges.
std::string index_ranges(const std::vector<std::size_t>& indices) {
  std::string out;
  for (std::size_t k = 0; k < indices.size();) {
    std::size_t end = k;
    while (end + 1 < indices.size() && indices[end + 1] == indices[end] + 1) ++end;
    out += (out.empty() ? "" : ", ") + std::to_string(indices[k]) + (end > k ? "-" + std::to_string(indices[end]) : "");
    k = end + 1;
  }
  return out;
}

/// The members' warnings, each text once with the members that gave it (a family
/// of 100 logs of one kind gives the same note 100 times), in first-seen order.
std::vector<std::pair<std::string, std::string>> grouped_warnings(const std::vector<MemberOutcome>& members) {
  std::vector<std::pair<std::string, std::vector<std::size_t>>> groups;
  for (std::size_t k = 0; k < members.size(); ++k)
    for (const std::string& w : members[k].identified.warnings) {
      auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == w; });
      if (it == groups.end()) {
        groups.emplace_back(w, std::vector<std::size_t>{});
        it = groups.end() - 1;
      }
      if (it->second.empty() || it->second.back() != k) it->second.push_back(k);
    }
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& [text, who] : groups)
    out.emplace_back(text, (who.size() == 1 ? "member " : "members ") + index_ranges(who) + " (" + std::to_string(who.size()) +
                               " of " + std::to_string(members.size()) + ")");
  return out;
}

void run_family(const FamilyArgs& a, const std::vector<std::string>& rest) {
  const std::string verb = "family";
  if (a.methods.empty()) throw CLI::RequiredError("--method");
  const std::string& method_name = a.methods.front();
  std::vector<std::string> method_args = rest;
  for (std::size_t k = 1; k < a.methods.size(); ++k) method_args.insert(method_args.end(), {"--method", a.methods[k]});
  const std::unique_ptr<MethodParser> method = parse_method(method_name, method_args);
  // The method's parser took the manifest as its log.
  const std::string manifest_path = method->verb.command->get_option("log")->as<std::string>();
  const FamilyManifest manifest = read_family_manifest(manifest_path);
  std::vector<std::string> inputs{manifest_path};
  for (const FamilyManifestRow& row : manifest.rows) {
    inputs.push_back(row.log_path);
    if (!row.validate_path.empty()) inputs.push_back(row.validate_path);
  }
  claim_outputs({a.out, a.plot}, inputs);

  ModelFamilyOptions options;
  options.bound.form = uncertainty_form_from_name(a.uncertainty);
  options.weight_order = a.weight_order;
  if (!a.band.empty()) options.band_hz = parse_range(a.band, "--band");

  std::vector<MemberOutcome> members = identify_members(method->verb, manifest);
  std::vector<FamilyMemberModel> models;
  for (const MemberOutcome& m : members) models.push_back({m.analysis_model, m.error});
  const ModelFamilyResult family = analyse_model_family(models, options);

  const bool time_series = members.front().identified.file.model.inputs() == 0;  // the same method and columns for all
  std::vector<FamilyFileMember> file_members;
  bool validated = false;
  for (std::size_t k = 0; k < members.size(); ++k) {
    FamilyFileMember fm;
    fm.log = manifest.rows[k].log;
    fm.validate = manifest.rows[k].validate;
    validated = validated || !fm.validate.empty();
    fm.model = members[k].identified.file;
    fm.fit_percent = members[k].fit_percent;
    file_members.push_back(std::move(fm));
  }
  const FamilyFile file = make_family_file(std::move(file_members), manifest.conditions, family, options);
  const int nominal = *file.nominal_member;

  // Report.
  std::ostringstream report;
  report << "family of " << members.size() << " members from " << manifest_path << ", each by sysid " << method_name << "\n"
         << members_table(manifest, members, file.outputs, validated, time_series);
  if (time_series)
    report << "time series: the modes and the bound are those of the noise models H L (unit white noise in, L L' the "
              "innovation covariance)\n";
  report << "band: " << fmt(family.band_lo_hz, 4) << " .. " << fmt(family.band_hi_hz, 4) << " Hz (" << family.band_source << ")\n";
  report << modes_table(file.modes, file.mode_spreads, members.size());
  report << "nominal: member " << nominal << " (" << file.nominal_criterion << ")\n";
  if (family.bound) {
    Eigen::Index peak_at = 0;
    const double peak = family.bound->bound.maxCoeff(&peak_at);
    report << "uncertainty (" << to_string(options.bound.form) << ", " << family.frequency_hz.size()
           << " frequencies): bound peak " << fmt(peak, 4) << " at " << fmt(family.frequency_hz(peak_at), 5)
           << " Hz, median " << fmt(median(std::vector<double>(family.bound->bound.data(), family.bound->bound.data() + family.bound->bound.size())), 4) << "; members' own spread peak "
           << fmt(family.bound->spread.maxCoeff(), 4) << "\n";
    if (family.weight)
      report << "weight W: order " << family.weight->weight.order() << ", stable and minimum-phase, |W| >= bound at every "
             << "frequency (min ratio " << fmt(family.weight->min_ratio, 6) << "); conservatism |W| / bound median "
             << fmt(family.weight->median_conservatism, 4) << ", largest " << fmt(family.weight->max_conservatism, 4) << "\n";
  }
  std::cout << report.str() << std::flush;
  for (const auto& [text, who] : grouped_warnings(members)) warn(verb, who + ": " + text);
  for (const std::string& w : family.warnings) warn(verb, w);
  if (!a.out.empty()) {
    write_family_json(a.out, file);
    note(verb, "wrote " + a.out);
  }
  if (!a.plot.empty()) plot_family(a.plot, members, family, manifest, nominal, options.bound.form);
}

}  // namespace

Verb register_family(CLI::App& app) {
  auto args = std::make_shared<FamilyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "family", "Identify one model per experiment of a manifest and derive the modes' spread, a nominal and an uncertainty weight");
  cmd->allow_extras();
  cmd->add_option("--method", args->methods,
                  "identification verb for every member (n4sid, arx, armax, oe, ar, arma ...); the manifest and every "
                  "option family does not know go to it, as 'sysid METHOD MANIFEST.csv OPTIONS' would take them; a "
                  "second --method is the verb's own (--method ar --method myw)")
      ->required()
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--band", args->band, "LO:HI Hz: band of the modes and the bound (default: the band every log excites)")
      ->check(range_validator());
  cmd->add_option("--uncertainty", args->uncertainty, "form of the bound: multiplicative-output, multiplicative-input or additive")
      ->capture_default_str()
      ->check(CLI::IsMember({"multiplicative-output", "multiplicative-input", "additive"}));
  cmd->add_option("--weight-order", args->weight_order, "poles of the uncertainty weight W (1..6)")
      ->capture_default_str()
      ->check(CLI::Range(1, 6));
  cmd->add_option("--out", args->out, "family file to write (JSON, DESIGN.md 'Model families')");
  cmd->add_option("--plot", args->plot,
                  "Bode magnitude of the members with the nominal, the bound and the weight, and the modes against each "
                  "condition (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->footer(
      "MANIFEST.csv: a header row and one row per experiment: 'log' (a CSV log, relative to the\n"
      "manifest's folder), optional 'validate' (a second log of the same condition) and any condition\n"
      "columns (numbers or labels). Members are identified in parallel on the cores.\n"
      "Prints the members with their fits, each mode's frequency and damping across the members with\n"
      "its trend per condition, the nominal and the bound; writes the family file at the end, atomically.\n"
      "Example:\n"
      "  sysid family runs/manifest.csv --inputs u --outputs y --method n4sid --order 8 --out family.json\n"
      "  sysid family gvt.csv --inputs u --outputs y1,y2,y3 --method n4sid --order 20 --band 2:15 --plot family.svg");
  return {cmd, [args, cmd] { run_family(*args, cmd->remaining()); }};
}

}  // namespace sysid::cli
