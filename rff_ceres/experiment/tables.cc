#include "rff_ceres/experiment/tables.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rff_ceres/experiment/grid.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {
namespace {

std::string Int(int value) { return std::to_string(value); }

// Settings columns: 0 landmarks and seed -1 mean "not a setting".
std::string LandmarksCell(int landmarks) {
  return landmarks > 0 ? Int(landmarks) : "";
}
std::string SeedCell(int seed) { return seed >= 0 ? Int(seed) : ""; }

std::string MedianMean(const Spread& spread) {
  if (spread.count == 0) return "-";
  return FormatSignificant(spread.median) + " / " +
         FormatSignificant(spread.mean);
}

// The failed runs under a Markdown table, so that a "failed" count or
// status is explained where it is read.
std::string FailureList(const std::vector<RunRow>& rows) {
  std::string text;
  int listed = 0, failed = 0;
  constexpr int kMaxListed = 10;
  for (const RunRow& row : rows) {
    if (row.ok()) continue;
    ++failed;
    if (listed == kMaxListed) continue;
    ++listed;
    text += "- " + row.method + " on " + row.dataset +
            (row.variant.empty() ? "" : " (" + row.variant + ")") + ": " +
            row.status.substr(row.status.find(':') + 2) + "\n";
  }
  if (failed == 0) return "";
  if (failed > listed) {
    text += "- ... and " + Int(failed - listed) + " more (runs.csv)\n";
  }
  return "\nFailed runs (" + Int(failed) + "):\n\n" + text;
}

std::string MarkdownDocument(const std::string& title,
                             const std::string& description, const Table& table,
                             const std::vector<RunRow>& rows) {
  return "# " + title + "\n\n" + description + "\n\n" + ToMarkdown(table) +
         FailureList(rows);
}

}  // namespace

std::string CsvField(const std::string& field) {
  if (field.find_first_of(",\"\r\n") == std::string::npos) return field;
  return "\"" + ReplaceAll(field, "\"", "\"\"") + "\"";
}

std::string ToCsv(const Table& table) {
  std::string text;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      text += (i > 0 ? "," : "") + CsvField(cells[i]);
    }
    text += "\n";
  };
  line(table.header);
  for (const auto& row : table.rows) line(row);
  return text;
}

std::string ToMarkdown(const Table& table) {
  std::string text;
  auto line = [&](const std::vector<std::string>& cells) {
    text += "|";
    for (const std::string& cell : cells) {
      std::string escaped = ReplaceAll(cell, "|", "\\|");
      escaped = ReplaceAll(escaped, "\n", " ");
      text += " " + (escaped.empty() ? std::string("-") : escaped) + " |";
    }
    text += "\n";
  };
  line(table.header);
  text += "|";
  for (std::size_t i = 0; i < table.header.size(); ++i) text += " --- |";
  text += "\n";
  for (const auto& row : table.rows) line(row);
  return text;
}

std::string FormatSignificant(double value) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  const double magnitude = std::fabs(value);
  if (magnitude >= 1000.0) {
    std::snprintf(buffer, sizeof(buffer), "%.0f", value);
  } else if (magnitude == 0.0) {
    return "0";
  } else {
    const int decimals =
        std::max(0, 2 - static_cast<int>(std::floor(std::log10(magnitude))));
    std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  }
  return buffer;
}

std::string FormatCsvNumber(double value) {
  return std::isfinite(value) ? FormatNumber(value) : "";
}

Table RunsCsvTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"experiment",     "method",
                  "dataset",        "family",
                  "kind",           "landmarks",
                  "noise",          "noise_unit",
                  "seed",           "variant",
                  "linear_solver",  "features",
                  "num_features",   "status",
                  "ape_trans_m",    "ape_rot_deg",
                  "rpe_trans_m",    "rpe_rot_deg",
                  "landmark_rms_m", "dead_reckoning_ape_trans_m",
                  "iterations",     "final_cost",
                  "solve_seconds"};
  for (const RunRow& r : rows) {
    table.rows.push_back({r.experiment,
                          r.method,
                          r.dataset,
                          r.family,
                          r.kind,
                          LandmarksCell(r.landmarks),
                          r.noise != 0.0 ? FormatCsvNumber(r.noise) : "",
                          r.noise_unit,
                          SeedCell(r.seed),
                          r.variant,
                          r.linear_solver,
                          r.features,
                          r.num_features > 0 ? Int(r.num_features) : "",
                          r.status,
                          FormatCsvNumber(r.ape_translation),
                          FormatCsvNumber(r.ape_rotation_deg),
                          FormatCsvNumber(r.rpe_translation),
                          FormatCsvNumber(r.rpe_rotation_deg),
                          FormatCsvNumber(r.landmark_rms),
                          FormatCsvNumber(r.dead_reckoning_ape_translation),
                          r.ok() ? Int(r.iterations) : "",
                          FormatCsvNumber(r.final_cost),
                          FormatCsvNumber(r.solve_seconds)});
  }
  return table;
}

Table Table1CsvTable(const std::vector<SeedAggregate>& aggregates) {
  Table table;
  table.header = {"method", "family",     "kind", "landmarks",
                  "noise",  "noise_unit", "runs", "failed"};
  const std::vector<std::string> metrics = {
      "ape_trans_m",  "ape_rot_deg",    "rpe_trans_m",
      "rpe_rot_deg",  "landmark_rms_m", "dead_reckoning_ape_trans_m",
      "solve_seconds"};
  for (const std::string& m : metrics) {
    table.header.push_back(m + "_median");
    table.header.push_back(m + "_mean");
  }
  for (const SeedAggregate& a : aggregates) {
    std::vector<std::string> row = {a.method,
                                    a.family,
                                    a.kind,
                                    LandmarksCell(a.landmarks),
                                    FormatCsvNumber(a.noise),
                                    a.noise_unit,
                                    Int(a.runs),
                                    Int(a.failed)};
    for (const Spread* s :
         {&a.ape_translation, &a.ape_rotation_deg, &a.rpe_translation,
          &a.rpe_rotation_deg, &a.landmark_rms,
          &a.dead_reckoning_ape_translation, &a.solve_seconds}) {
      row.push_back(FormatCsvNumber(s->median));
      row.push_back(FormatCsvNumber(s->mean));
    }
    table.rows.push_back(row);
  }
  return table;
}

Table Table1MarkdownTable(const std::vector<SeedAggregate>& aggregates) {
  Table table;
  table.header = {"method",
                  "kind",
                  "landmarks",
                  "noise",
                  "ok / runs",
                  "APE-trans [m] median / mean",
                  "APE-rot [deg] median / mean",
                  "RPE-trans [m] median / mean",
                  "RPE-rot [deg] median / mean",
                  "landmarks [m] median / mean",
                  "dead reckoning APE-trans [m] median",
                  "time [s] mean"};
  for (const SeedAggregate& a : aggregates) {
    table.rows.push_back(
        {a.method, a.kind, LandmarksCell(a.landmarks),
         NoiseLabel(a.noise, a.noise_unit),
         Int(a.runs - a.failed) + " / " + Int(a.runs),
         MedianMean(a.ape_translation), MedianMean(a.ape_rotation_deg),
         MedianMean(a.rpe_translation), MedianMean(a.rpe_rotation_deg),
         MedianMean(a.landmark_rms),
         FormatSignificant(a.dead_reckoning_ape_translation.median),
         FormatSignificant(a.solve_seconds.mean)});
  }
  return table;
}

Table Table2CsvTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"method",
                  "dataset",
                  "family",
                  "noise",
                  "noise_unit",
                  "ape_trans_m",
                  "ape_rot_deg",
                  "rpe_trans_m",
                  "rpe_rot_deg",
                  "landmark_rms_m",
                  "dead_reckoning_ape_trans_m",
                  "iterations",
                  "final_cost",
                  "solve_seconds",
                  "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back(
        {r.method, r.dataset, r.family,
         r.noise != 0.0 ? FormatCsvNumber(r.noise) : "", r.noise_unit,
         FormatCsvNumber(r.ape_translation),
         FormatCsvNumber(r.ape_rotation_deg),
         FormatCsvNumber(r.rpe_translation),
         FormatCsvNumber(r.rpe_rotation_deg), FormatCsvNumber(r.landmark_rms),
         FormatCsvNumber(r.dead_reckoning_ape_translation),
         r.ok() ? Int(r.iterations) : "", FormatCsvNumber(r.final_cost),
         FormatCsvNumber(r.solve_seconds), r.status});
  }
  return table;
}

Table Table2MarkdownTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"method",        "dataset",
                  "family",        "noise",
                  "APE-trans [m]", "APE-rot [deg]",
                  "RPE-trans [m]", "RPE-rot [deg]",
                  "landmarks [m]", "dead reckoning APE-trans [m]",
                  "iterations",    "final cost",
                  "time [s]",      "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back(
        {r.method, r.dataset, r.family, NoiseLabel(r.noise, r.noise_unit),
         FormatSignificant(r.ape_translation),
         FormatSignificant(r.ape_rotation_deg),
         FormatSignificant(r.rpe_translation),
         FormatSignificant(r.rpe_rotation_deg),
         FormatSignificant(r.landmark_rms),
         FormatSignificant(r.dead_reckoning_ape_translation),
         r.ok() ? Int(r.iterations) : "-", FormatSignificant(r.final_cost),
         FormatSignificant(r.solve_seconds), r.ok() ? "ok" : "failed"});
  }
  return table;
}

Table SolversCsvTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"method",     "dataset",      "linear_solver",
                  "features",   "num_features", "solve_seconds",
                  "iterations", "final_cost",   "ape_trans_m",
                  "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back({r.method, r.dataset, r.linear_solver, r.features,
                          r.num_features > 0 ? Int(r.num_features) : "",
                          FormatCsvNumber(r.solve_seconds),
                          r.ok() ? Int(r.iterations) : "",
                          FormatCsvNumber(r.final_cost),
                          FormatCsvNumber(r.ape_translation), r.status});
  }
  return table;
}

Table SolversMarkdownTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {
      "method",   "dataset",    "linear solver", "features",      "D",
      "time [s]", "iterations", "final cost",    "APE-trans [m]", "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back(
        {r.method, r.dataset, r.linear_solver, r.features,
         r.num_features > 0 ? Int(r.num_features) : "-",
         FormatSignificant(r.solve_seconds), r.ok() ? Int(r.iterations) : "-",
         FormatSignificant(r.final_cost), FormatSignificant(r.ape_translation),
         r.ok() ? "ok" : "failed"});
  }
  return table;
}

std::string Table1MarkdownDocument(const std::vector<SeedAggregate>& aggregates,
                                   const std::vector<RunRow>& rows,
                                   const std::string& method_names) {
  return MarkdownDocument(
      "Table I: simulated sets (paper protocol)",
      "Methods: " + method_names +
          ". 300 poses at 1 s, 4 landmarks observed per pose, "
          "sigma_r = 1 m, sigma_b = 2 deg, odometry 0.05 m / "
          "0.01 rad; median / mean over seeds of the RMS errors "
          "(APE without alignment). Time: the whole solve.",
      Table1MarkdownTable(aggregates), rows);
}

std::string Table2MarkdownDocument(const std::vector<RunRow>& rows,
                                   const std::string& method_names,
                                   bool quick) {
  return MarkdownDocument("Table II: real data and KITTI-scale bearing-only",
                          "Methods: " + method_names +
                              ". CMU Plaza 1 (range-only), UTIAS MRCLAM 6 "
                              "(range-bearing) and the simulated KITTI-scale "
                              "bearing-only set with bearing sigma 1, 3 and 5 "
                              "deg" +
                              (quick ? " (quick: 600 poses)" : "") +
                              "; RMS errors, APE without alignment.",
                          Table2MarkdownTable(rows), rows);
}

std::string SolversMarkdownDocument(const std::vector<RunRow>& rows,
                                    const std::string& method_names) {
  return MarkdownDocument("Linear solvers and feature families",
                          "Methods: " + method_names +
                              ", each with its config and the linear solver, "
                              "feature family and D (features per coordinate) "
                              "overridden. Time: the whole solve.",
                          SolversMarkdownTable(rows), rows);
}

}  // namespace rff
