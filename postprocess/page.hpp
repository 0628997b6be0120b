// One page written twice: as Markdown (report.md) and as a self-contained HTML file (report.html,
// images embedded as base64 data URIs, no external file or script), from the same blocks, so the
// two never disagree. Used by `swmpm study` (study/report.cpp) and the run report (report.cpp).
#pragma once

#include <string>
#include <vector>

namespace swmpm::post {

struct Page {
  /// A heading (level 1-3), a paragraph, a bullet list, a table, or an image. Text is plain:
  /// `code` spans and **bold** are the only markup, rendered in both formats.
  struct Block {
    enum Kind { heading, paragraph, bullets, table, image } kind = paragraph;
    int level = 2;                                  // heading
    std::string text;                               // heading, paragraph; image: its caption
    std::vector<std::string> items;                 // bullets; table: the header cells
    std::vector<std::vector<std::string>> rows;     // table
    std::string path;                               // image: the PNG file (relative to the page in Markdown)
  };
  std::string title;
  std::vector<Block> blocks;

  void add_heading(const std::string& text, int level = 2) { blocks.push_back({Block::heading, level, text, {}, {}, {}}); }
  void add_paragraph(const std::string& text) { blocks.push_back({Block::paragraph, 0, text, {}, {}, {}}); }
  void add_bullets(std::vector<std::string> items) { blocks.push_back({Block::bullets, 0, {}, std::move(items), {}, {}}); }
  void add_table(std::vector<std::string> header, std::vector<std::vector<std::string>> rows) {
    blocks.push_back({Block::table, 0, {}, std::move(header), std::move(rows), {}});
  }
  /// `path` relative to the folder the page is written in.
  void add_image(const std::string& caption, const std::string& path) {
    blocks.push_back({Block::image, 0, caption, {}, {}, path});
  }

  std::string markdown() const;
  /// The HTML page; images are read from `folder` / path and embedded (throws when one is missing).
  std::string html(const std::string& folder) const;
};

/// RFC 4648 base64 of bytes (VTK's encoder).
std::string base64(const std::string& bytes);

}  // namespace swmpm::post
