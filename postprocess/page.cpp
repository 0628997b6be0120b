#include "postprocess/page.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include <vtkBase64Utilities.h>

namespace swmpm::post {

namespace {

/// A Markdown table cell: '|' would end the cell, a newline the row.
std::string md_cell(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '|' ? std::string("\\|") : c == '\n' ? std::string(" ") : std::string(1, c);
  return out;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// Escaped text with `code` and **bold** rendered as <code> and <strong>.
std::string inline_html(const std::string& s) {
  std::string out;
  bool code = false, bold = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '`') {
      out += code ? "</code>" : "<code>";
      code = !code;
    } else if (!code && s.compare(i, 2, "**") == 0) {
      out += bold ? "</strong>" : "<strong>";
      bold = !bold;
      ++i;
    } else {
      out += escape(std::string(1, s[i]));
    }
  }
  if (code) out += "</code>";
  if (bold) out += "</strong>";
  return out;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot read the image to embed");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

std::string base64(const std::string& bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3), '\0');
  const unsigned long n = vtkBase64Utilities::Encode(reinterpret_cast<const unsigned char*>(bytes.data()),
                                                     static_cast<unsigned long>(bytes.size()),
                                                     reinterpret_cast<unsigned char*>(out.data()));
  out.resize(n);
  return out;
}

std::string Page::markdown() const {
  std::ostringstream md;
  md << "# " << title << "\n\n";
  for (const Block& b : blocks) {
    switch (b.kind) {
      case Block::heading: md << std::string(static_cast<std::size_t>(b.level), '#') << " " << b.text << "\n\n"; break;
      case Block::paragraph: md << b.text << "\n\n"; break;
      case Block::bullets:
        for (const auto& item : b.items) md << "- " << item << "\n";
        md << "\n";
        break;
      case Block::table:
        md << "|";
        for (const auto& h : b.items) md << " " << md_cell(h) << " |";
        md << "\n|";
        for (std::size_t k = 0; k < b.items.size(); ++k) md << "---|";
        md << "\n";
        for (const auto& row : b.rows) {
          md << "|";
          for (const auto& c : row) md << " " << md_cell(c) << " |";
          md << "\n";
        }
        md << "\n";
        break;
      case Block::image: md << "![" << b.text << "](" << b.path << ")\n\n" << b.text << "\n\n"; break;
    }
  }
  return md.str();
}

std::string Page::html(const std::string& folder) const {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << escape(title)
    << "</title>\n<style>\n"
    << "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}\n"
    << "table{border-collapse:collapse;margin:1em 0;font-size:0.92em}\n"
    << "th,td{border:1px solid #bbb;padding:0.3em 0.6em;text-align:left;vertical-align:top}\n"
    << "th{background:#eef2f6}\ncode{background:#f3f3f3;padding:0 0.2em}\nimg{max-width:100%}\n"
    << "figcaption{font-size:0.9em;color:#555}\n</style>\n</head>\n<body>\n<h1>" << inline_html(title) << "</h1>\n";
  for (const Block& b : blocks) {
    switch (b.kind) {
      case Block::heading: h << "<h" << b.level << ">" << inline_html(b.text) << "</h" << b.level << ">\n"; break;
      case Block::paragraph: h << "<p>" << inline_html(b.text) << "</p>\n"; break;
      case Block::bullets:
        h << "<ul>\n";
        for (const auto& item : b.items) h << "<li>" << inline_html(item) << "</li>\n";
        h << "</ul>\n";
        break;
      case Block::table:
        // An all-empty header is a key-value table: no header row, the keys as row headers.
        if (std::all_of(b.items.begin(), b.items.end(), [](const std::string& c) { return c.empty(); })) {
          h << "<table>\n";
          for (const auto& row : b.rows) {
            h << "<tr>";
            for (std::size_t k = 0; k < row.size(); ++k)
              h << (k == 0 ? "<th>" : "<td>") << inline_html(row[k]) << (k == 0 ? "</th>" : "</td>");
            h << "</tr>\n";
          }
          h << "</table>\n";
          break;
        }
        h << "<table>\n<tr>";
        for (const auto& c : b.items) h << "<th>" << inline_html(c) << "</th>";
        h << "</tr>\n";
        for (const auto& row : b.rows) {
          h << "<tr>";
          for (const auto& c : row) h << "<td>" << inline_html(c) << "</td>";
          h << "</tr>\n";
        }
        h << "</table>\n";
        break;
      case Block::image:
        h << "<figure><img alt=\"" << escape(b.text) << "\" src=\"data:image/png;base64,"
          << base64(read_bytes(std::filesystem::path(folder) / b.path)) << "\"><figcaption>" << inline_html(b.text)
          << "</figcaption></figure>\n";
        break;
    }
  }
  h << "</body>\n</html>\n";
  return h.str();
}

}  // namespace swmpm::post
