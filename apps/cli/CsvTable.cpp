// CsvTable: a small, strict CSV reader for numeric tables.
#include "CsvTable.h"

#include "Checker.h"

#include <cerrno>
#include <cstdlib>
#include <fmt/format.h>

namespace facet {

namespace {
std::string trim(const std::string& s) {
    size_t b = s.find_first_not_of(" \t\r");
    if (b == std::string::npos) return "";
    size_t e = s.find_last_not_of(" \t\r");
    return s.substr(b, e - b + 1);
}

}  // namespace

std::vector<std::string> splitFields(const std::string& line) {
    std::vector<std::string> out;
    size_t start = 0;
    for (;;) {
        size_t comma = line.find(',', start);
        out.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
        if (comma == std::string::npos) return out;
        start = comma + 1;
    }
}

int CsvTable::columnIndex(const std::string& name) const {
    for (size_t i = 0; i < columns.size(); ++i)
        if (columns[i] == name) return int(i);
    return -1;
}

std::optional<double> parseNumber(const std::string& field) {
    std::string f = trim(field);
    if (f.empty()) return std::nullopt;
    errno = 0;
    char* end = nullptr;
    double v = std::strtod(f.c_str(), &end);
    if (end != f.c_str() + f.size()) return std::nullopt;
    return v;
}

std::optional<CsvTable> readCsv(const std::string& path, std::string& error) {
    std::optional<std::string> text = readSourceFile(path, error);
    if (!text) {
        error = fmt::format("{}: error: {}", path, error);
        return std::nullopt;
    }
    // A UTF-8 byte order mark is not part of the first column's name.
    if (text->compare(0, 3, "\xEF\xBB\xBF") == 0) text->erase(0, 3);
    CsvTable table;
    std::string line;
    int lineNo = 0;
    bool haveHeader = false;
    // Lines end at "\n", "\r\n" or a lone "\r".
    for (size_t pos = 0; pos < text->size();) {
        size_t end = text->find_first_of("\r\n", pos);
        if (end == std::string::npos) end = text->size();
        line = text->substr(pos, end - pos);
        pos = end + ((*text)[end] == '\r' && end + 1 < text->size() && (*text)[end + 1] == '\n' ? 2 : 1);
        ++lineNo;
        if (trim(line).empty()) continue;
        std::vector<std::string> fields = splitFields(line);
        if (!haveHeader) {
            for (size_t i = 0; i < fields.size(); ++i)
                for (size_t j = 0; j < i; ++j)
                    if (fields[i] == fields[j]) {
                        error = fmt::format("{}:{}: error: column '{}' appears twice (columns {} and {})", path,
                                            lineNo, fields[i], j + 1, i + 1);
                        return std::nullopt;
                    }
            table.columns = fields;
            haveHeader = true;
            continue;
        }
        CsvRow row;
        row.line = lineNo;
        if (fields.size() != table.columns.size()) {
            row.error = fmt::format("expected {} columns, found {}", table.columns.size(), fields.size());
        } else {
            for (size_t i = 0; i < fields.size(); ++i) {
                std::optional<double> v = parseNumber(fields[i]);
                if (!v) {
                    row.error = fmt::format("column '{}' is not a number: '{}'", table.columns[i], fields[i]);
                    break;
                }
                row.values.push_back(*v);
            }
        }
        table.rows.push_back(std::move(row));
    }
    if (!haveHeader) {
        error = fmt::format("{}: error: empty file (expected a header line such as "
                            "wi_x,wi_y,wi_z,wo_x,wo_y,wo_z)",
                            path);
        return std::nullopt;
    }
    return table;
}

}  // namespace facet
