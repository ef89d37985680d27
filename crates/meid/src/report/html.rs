//! A minimal, self-contained HTML page model: sections of paragraphs, lists, figures with
//! captions and tables. Text is always escaped; no scripts, no network resources.

use std::fmt::Write as _;
use std::path::Path;

use crate::{Error, Result};

/// A figure: one picture file (relative to the page's directory, e.g. `fig03.svg`) with its
/// caption. Each figure is numbered in page order when rendered.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Figure {
    /// Relative path of the picture (PNG or SVG) from the page's directory.
    pub src: String,
    /// Alternative text (what the picture shows, for screen readers).
    pub alt: String,
    /// Caption below the picture. Must not be empty ([`check_page`] refuses a figure without one).
    pub caption: String,
    /// Relative paths of the figure's data files (CSV/JSON), linked under the caption.
    pub data: Vec<String>,
}

/// A table with a caption, a header row and body rows of cell text.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Caption above the table.
    pub caption: String,
    /// Column headings.
    pub header: Vec<String>,
    /// Rows of cells; a row shorter than the header is padded with empty cells.
    pub rows: Vec<Vec<String>>,
    /// Optional CSS class per row (e.g. `"ok"`, `"shape"`, `"no"` for verdicts); empty = none.
    pub row_class: Vec<String>,
}

/// One block of a section.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A paragraph of plain text (escaped).
    Paragraph(String),
    /// A bulleted list of plain-text items.
    List(Vec<String>),
    /// A figure with caption.
    Figure(Figure),
    /// A table.
    Table(Table),
    /// Preformatted text (escaped), e.g. a command line or a model summary.
    Pre(String),
}

/// A titled section of a page (an `h2` with an anchor `id`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Section {
    /// Anchor name (letters, digits, `-`), used by the table of contents.
    pub id: String,
    /// Heading text.
    pub heading: String,
    /// Content in order.
    pub blocks: Vec<Block>,
}

/// A whole page: title, an optional lead paragraph, a table of contents built from the
/// sections, then the sections.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Page {
    /// `<title>` and `h1`.
    pub title: String,
    /// Text under the title (e.g. what produced the page and when).
    pub lead: String,
    /// Sections in order.
    pub sections: Vec<Section>,
}

/// Escapes `&`, `<`, `>`, `"` and `'` for HTML text and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;\
line-height:1.45;color:#222}h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;\
margin-top:2em}figure{margin:1.5em 0}figure img{max-width:100%;border:1px solid #eee}\
figcaption{font-size:.92em;color:#333;margin-top:.4em}table{border-collapse:collapse;margin:1em 0;\
font-size:.9em}caption{text-align:left;font-weight:bold;margin-bottom:.4em}th,td{border:1px solid #ccc;\
padding:.25em .5em;vertical-align:top;text-align:left}th{background:#f3f3f3}tr.ok td{background:#eef8ee}\
tr.shape td{background:#fff8e5}tr.no td{background:#fdecec}pre{background:#f6f6f6;padding:.6em;\
overflow-x:auto}nav ol{columns:2}.data{font-size:.85em}";

impl Page {
    /// Renders the page to one HTML5 document (UTF-8, CSS inline, no scripts).
    pub fn to_html(&self) -> String {
        let mut s = String::new();
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
            escape(&self.title),
            escape(&self.title)
        );
        if !self.lead.is_empty() {
            let _ = writeln!(s, "<p class=\"lead\">{}</p>", escape(&self.lead));
        }
        if self.sections.len() > 1 {
            s.push_str("<nav><ol>\n");
            for sec in &self.sections {
                let _ = writeln!(
                    s,
                    "<li><a href=\"#{}\">{}</a></li>",
                    escape(&sec.id),
                    escape(&sec.heading)
                );
            }
            s.push_str("</ol></nav>\n");
        }
        let mut figure_no = 0usize;
        let mut table_no = 0usize;
        for sec in &self.sections {
            let _ = writeln!(
                s,
                "<section id=\"{}\">\n<h2>{}</h2>",
                escape(&sec.id),
                escape(&sec.heading)
            );
            for block in &sec.blocks {
                match block {
                    Block::Paragraph(p) => {
                        let _ = writeln!(s, "<p>{}</p>", escape(p));
                    }
                    Block::List(items) => {
                        s.push_str("<ul>\n");
                        for item in items {
                            let _ = writeln!(s, "<li>{}</li>", escape(item));
                        }
                        s.push_str("</ul>\n");
                    }
                    Block::Pre(text) => {
                        let _ = writeln!(s, "<pre>{}</pre>", escape(text));
                    }
                    Block::Figure(f) => {
                        figure_no += 1;
                        let _ = write!(
                            s,
                            "<figure id=\"figure-{figure_no}\">\n<img src=\"{}\" alt=\"{}\">\n\
                             <figcaption><b>Figure {figure_no}.</b> {}",
                            escape(&f.src),
                            escape(&f.alt),
                            escape(&f.caption)
                        );
                        if !f.data.is_empty() {
                            s.push_str(" <span class=\"data\">Data:");
                            for d in &f.data {
                                let _ = write!(s, " <a href=\"{}\">{}</a>", escape(d), escape(d));
                            }
                            s.push_str("</span>");
                        }
                        s.push_str("</figcaption>\n</figure>\n");
                    }
                    Block::Table(t) => {
                        table_no += 1;
                        let _ = writeln!(
                            s,
                            "<table id=\"table-{table_no}\">\n<caption>Table {table_no}. {}</caption>",
                            escape(&t.caption)
                        );
                        s.push_str("<thead><tr>");
                        for h in &t.header {
                            let _ = write!(s, "<th>{}</th>", escape(h));
                        }
                        s.push_str("</tr></thead>\n<tbody>\n");
                        for (i, row) in t.rows.iter().enumerate() {
                            match t.row_class.get(i).filter(|c| !c.is_empty()) {
                                Some(c) => {
                                    let _ = write!(s, "<tr class=\"{}\">", escape(c));
                                }
                                None => s.push_str("<tr>"),
                            }
                            let width = t.header.len().max(row.len());
                            for j in 0..width {
                                let cell = row.get(j).map(String::as_str).unwrap_or("");
                                let _ = write!(s, "<td>{}</td>", escape(cell));
                            }
                            s.push_str("</tr>\n");
                        }
                        s.push_str("</tbody>\n</table>\n");
                    }
                }
            }
            s.push_str("</section>\n");
        }
        s.push_str("</body>\n</html>\n");
        s
    }

    /// Writes the page atomically to `path` (the pictures it names must be written beside it
    /// by the caller).
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::io::write_atomic(path, self.to_html().as_bytes())
    }
}

/// A problem found by [`check_page`].
#[derive(Debug, Clone, PartialEq)]
pub enum PageProblem {
    /// A `src` or `href` names a local file that does not exist in the page's directory.
    MissingFile(String),
    /// A `src`/`href` points outside the page's directory (absolute path, `..`, or a network URL).
    NotSelfContained(String),
    /// A `<figure>` without a non-empty `<figcaption>`; the figure's index (1-based).
    FigureWithoutCaption(usize),
}

impl std::fmt::Display for PageProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PageProblem::MissingFile(p) => write!(f, "{p}: referenced but missing"),
            PageProblem::NotSelfContained(p) => {
                write!(f, "{p}: not a relative file inside the page's directory")
            }
            PageProblem::FigureWithoutCaption(i) => write!(f, "figure {i} has no caption"),
        }
    }
}

/// Attribute values of `name="…"` in `html`, in order (the page's own renderer always quotes
/// with `"`).
fn attribute_values<'a>(html: &'a str, name: &str) -> Vec<&'a str> {
    let pattern = format!(" {name}=\"");
    let mut out = Vec::new();
    let mut rest = html;
    while let Some(i) = rest.find(&pattern) {
        let after = &rest[i + pattern.len()..];
        match after.find('"') {
            Some(j) => {
                out.push(&after[..j]);
                rest = &after[j..];
            }
            None => break,
        }
    }
    out
}

/// Reverses [`escape`] for the entities it produces.
fn unescape(text: &str) -> String {
    text.replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// Checks an HTML page written in `dir`: every `src` and every `href` that is not an in-page
/// anchor (`#…`) names an existing file inside `dir` by a relative path without `..`, and every
/// `<figure>` has a non-empty `<figcaption>`. Returns the problems found (empty = good).
pub fn check_page(dir: &Path, html: &str) -> Vec<PageProblem> {
    let mut problems = Vec::new();
    let mut targets = attribute_values(html, "src");
    targets.extend(attribute_values(html, "href"));
    for raw in targets {
        if raw.starts_with('#') {
            continue;
        }
        let target = unescape(raw);
        let path = Path::new(&target);
        let outside = target.contains("://")
            || target.starts_with("//")
            || path.is_absolute()
            || path
                .components()
                .any(|c| !matches!(c, std::path::Component::Normal(_)));
        if outside {
            problems.push(PageProblem::NotSelfContained(target));
        } else if !dir.join(path).is_file() {
            problems.push(PageProblem::MissingFile(target));
        }
    }
    for (i, figure) in html.split("<figure").skip(1).enumerate() {
        let body = figure.split("</figure>").next().unwrap_or("");
        let caption = body
            .split("<figcaption>")
            .nth(1)
            .and_then(|c| c.split("</figcaption>").next())
            .map(|c| {
                // Text without tags.
                let mut text = String::new();
                let mut in_tag = false;
                for ch in c.chars() {
                    match ch {
                        '<' => in_tag = true,
                        '>' => in_tag = false,
                        _ if !in_tag => text.push(ch),
                        _ => {}
                    }
                }
                text
            })
            .unwrap_or_default();
        // "Figure N." alone is not a caption.
        let meaningful = caption
            .trim()
            .trim_start_matches("Figure")
            .trim_start_matches(|c: char| c.is_ascii_digit() || c == ' ' || c == '.')
            .trim();
        if meaningful.is_empty() {
            problems.push(PageProblem::FigureWithoutCaption(i + 1));
        }
    }
    problems
}

/// Reads `path` and runs [`check_page`] on it; any problem is an error listing them all.
pub fn verify_page_file(path: &Path) -> Result<()> {
    let html = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let dir = path.parent().unwrap_or_else(|| Path::new("."));
    let problems = check_page(dir, &html);
    if problems.is_empty() {
        Ok(())
    } else {
        let list: Vec<String> = problems.iter().map(ToString::to_string).collect();
        Err(Error::Input {
            location: path.display().to_string(),
            message: format!("page is not self-contained: {}", list.join("; ")),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn page_with(src: &str, caption: &str) -> Page {
        Page {
            title: "T <&>".into(),
            lead: "lead".into(),
            sections: vec![Section {
                id: "s".into(),
                heading: "S".into(),
                blocks: vec![
                    Block::Figure(Figure {
                        src: src.into(),
                        alt: "a".into(),
                        caption: caption.into(),
                        data: vec![],
                    }),
                    Block::Table(Table {
                        caption: "c".into(),
                        header: vec!["a".into(), "b".into()],
                        rows: vec![vec!["1 < 2".into()]],
                        row_class: vec!["ok".into()],
                    }),
                ],
            }],
        }
    }

    #[test]
    fn text_is_escaped() {
        let html = page_with("x.png", "cap").to_html();
        assert!(html.contains("<title>T &lt;&amp;&gt;</title>"));
        assert!(html.contains("<td>1 &lt; 2</td><td></td>"));
        assert!(html.contains("<tr class=\"ok\">"));
        assert!(!html.contains("<script"));
    }

    #[test]
    fn check_finds_missing_outside_and_uncaptioned() {
        let dir = std::env::temp_dir().join(format!("meid-html-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("a b.png"), b"x").unwrap();
        let good = page_with("a b.png", "what it shows").to_html();
        assert_eq!(check_page(&dir, &good), vec![]);
        let missing = page_with("nope.png", "c").to_html();
        assert_eq!(
            check_page(&dir, &missing),
            vec![PageProblem::MissingFile("nope.png".into())]
        );
        for outside in ["../a b.png", "/etc/passwd", "https://x.org/a.png"] {
            let html = page_with(outside, "c").to_html();
            assert_eq!(
                check_page(&dir, &html),
                vec![PageProblem::NotSelfContained(outside.into())],
                "{outside}"
            );
        }
        let uncaptioned = page_with("a b.png", "").to_html();
        assert_eq!(
            check_page(&dir, &uncaptioned),
            vec![PageProblem::FigureWithoutCaption(1)]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
