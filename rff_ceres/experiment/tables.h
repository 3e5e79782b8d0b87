// The experiment's tables: every run (runs.csv), Table I over seeds, Table
// II and the solver comparison, each as CSV and as a Markdown document that
// says what was run and lists the failed runs.
#ifndef RFF_CERES_EXPERIMENT_TABLES_H_
#define RFF_CERES_EXPERIMENT_TABLES_H_

#include <string>
#include <vector>

#include "rff_ceres/experiment/aggregation.h"
#include "rff_ceres/experiment/runner.h"

namespace rff {

// A table of text cells, written as CSV or as Markdown.
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

// RFC 4180: a field with a comma, quote, CR or LF is quoted, quotes doubled.
std::string CsvField(const std::string& field);
std::string ToCsv(const Table& table);
// A GitHub Markdown table; '|' in cells is escaped.
std::string ToMarkdown(const Table& table);

// Number for Markdown: 3 significant digits (fixed notation, 0.000412 to
// 999; integers from 1000 up), "-" for NaN.
std::string FormatSignificant(double value);
// Number for CSV: the shortest exact form, "" for NaN.
std::string FormatCsvNumber(double value);

// Every column of every row (runs.csv).
Table RunsCsvTable(const std::vector<RunRow>& rows);
// Table I: seed aggregates; CSV with median and mean of every metric, the
// Markdown with "median / mean" cells.
Table Table1CsvTable(const std::vector<SeedAggregate>& aggregates);
Table Table1MarkdownTable(const std::vector<SeedAggregate>& aggregates);
// Table II: one row per run.
Table Table2CsvTable(const std::vector<RunRow>& rows);
Table Table2MarkdownTable(const std::vector<RunRow>& rows);
// Solver comparison: one row per run.
Table SolversCsvTable(const std::vector<RunRow>& rows);
Table SolversMarkdownTable(const std::vector<RunRow>& rows);

// The Markdown files (table1.md, table2.md, solvers.md): a title, the
// protocol with `method_names`, the table and the failed ones of `rows`.
// `quick` says in Table II that the KITTI-scale set is the short one.
std::string Table1MarkdownDocument(const std::vector<SeedAggregate>& aggregates,
                                   const std::vector<RunRow>& rows,
                                   const std::string& method_names);
std::string Table2MarkdownDocument(const std::vector<RunRow>& rows,
                                   const std::string& method_names, bool quick);
std::string SolversMarkdownDocument(const std::vector<RunRow>& rows,
                                    const std::string& method_names);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_TABLES_H_
