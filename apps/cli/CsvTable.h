// CsvTable: reading the numeric CSV files of `facet eval`.
//
// The header names the columns; each data row must have as many fields as
// the header. A row that does not parse is kept with its error so that the
// caller can report it by row number and still evaluate every other row.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace facet {

struct CsvRow {
    int line = 0;               // line in the file (1-based; the header is line 1)
    std::vector<double> values; // one per column when error is empty
    std::string error;          // what is wrong with this row, or empty
};

struct CsvTable {
    std::vector<std::string> columns;
    std::vector<CsvRow> rows;
    int columnIndex(const std::string& name) const;  // -1 if absent
};

// Reads `path`; returns nullopt and sets `error` if the file cannot be read
// or has no header. Row-level problems are stored in the rows.
std::optional<CsvTable> readCsv(const std::string& path, std::string& error);

// Parses a whole field as a number (leading/trailing blanks allowed). "nan"
// and "inf" parse (they are numbers, and the evaluator reports them).
std::optional<double> parseNumber(const std::string& field);

// Splits a line at commas, trimming blanks around each field ("a, b" ->
// {"a", "b"}; "" -> {""}). Also used for option values like --set NAME=r,g,b.
std::vector<std::string> splitFields(const std::string& line);

}  // namespace facet
