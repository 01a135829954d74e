//! A small report model written as both a self-contained folder with `index.html` and
//! `report.md` (figures are files next to them, referenced by relative paths).

use crate::artefact::OutDir;
use anyhow::Result;
use std::fmt::Write as _;

/// One block of content.
#[derive(Clone, Debug)]
pub enum Block {
    /// A section heading (`<h2>`, `##`).
    Heading(String),
    /// A paragraph of text.
    Paragraph(String),
    /// Column headers and rows of cells.
    Table(Vec<String>, Vec<Vec<String>>),
    /// A figure file relative to the report folder, and its caption.
    Figure(String, String),
    /// Preformatted text (commands, terminal output).
    Code(String),
    /// Markdown text (a sub-report), rendered as HTML; its headings sit two levels below the
    /// report's (`#` becomes `<h3>`).
    Markdown(String),
    /// The table of contents: a link to every heading of the document.
    Toc,
    /// A figure of side-by-side panels: the file, one label per panel (left to right), the
    /// caption.
    Panels(String, Vec<String>, String),
}

/// A report: a title and a flat list of blocks.
#[derive(Clone, Debug, Default)]
pub struct Document {
    /// Title (`<h1>`, `#`).
    pub title: String,
    /// Content, in order.
    pub blocks: Vec<Block>,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Escaped text with `code spans` as `<code>` (the report's prose is Markdown-flavoured).
fn inline(s: &str) -> String {
    let e = esc(s);
    let parts: Vec<&str> = e.split('`').collect();
    if parts.len() < 3 || parts.len().is_multiple_of(2) {
        return e;
    }
    let mut out = String::new();
    for (k, p) in parts.iter().enumerate() {
        if k % 2 == 1 {
            let _ = write!(out, "<code>{p}</code>");
        } else {
            out.push_str(p);
        }
    }
    out
}

/// Every `<img …>` after the first one with the same `src` replaced by a link to it: each image
/// is embedded once.
fn embed_images_once(html: &str) -> String {
    let mut seen: Vec<String> = Vec::new();
    let mut out = String::new();
    let mut rest = html;
    while let Some(p) = rest.find("<img ") {
        out.push_str(&rest[..p]);
        let tag_end = rest[p..].find('>').map_or(rest.len(), |e| p + e + 1);
        let tag = &rest[p..tag_end];
        let src = tag
            .split_once("src=\"")
            .and_then(|x| x.1.split_once('"'))
            .map(|x| x.0.to_string())
            .unwrap_or_default();
        if seen.contains(&src) {
            let _ = write!(out, "<a href=\"{src}\">{src} (shown above)</a>");
        } else {
            seen.push(src);
            out.push_str(tag);
        }
        rest = &rest[tag_end..];
    }
    out.push_str(rest);
    out
}

/// The anchor of the k-th heading.
fn anchor(k: usize) -> String {
    format!("s{k}")
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

impl Document {
    /// An empty document titled `title`.
    pub fn new(title: &str) -> Document {
        Document {
            title: title.to_string(),
            blocks: Vec::new(),
        }
    }
    /// Appends a [`Block::Heading`].
    pub fn heading(&mut self, s: impl Into<String>) {
        self.blocks.push(Block::Heading(s.into()));
    }
    /// Appends a [`Block::Paragraph`].
    pub fn paragraph(&mut self, s: impl Into<String>) {
        self.blocks.push(Block::Paragraph(s.into()));
    }
    /// Appends a [`Block::Table`].
    pub fn table(&mut self, headers: &[&str], rows: Vec<Vec<String>>) {
        self.blocks.push(Block::Table(
            headers.iter().map(|s| s.to_string()).collect(),
            rows,
        ));
    }
    /// Appends a [`Block::Figure`].
    pub fn figure(&mut self, file: impl Into<String>, caption: impl Into<String>) {
        self.blocks.push(Block::Figure(file.into(), caption.into()));
    }
    /// Appends a [`Block::Code`].
    pub fn code(&mut self, s: impl Into<String>) {
        self.blocks.push(Block::Code(s.into()));
    }
    /// Appends a [`Block::Toc`].
    pub fn toc(&mut self) {
        self.blocks.push(Block::Toc);
    }
    /// Appends a [`Block::Panels`].
    pub fn panels(&mut self, file: impl Into<String>, labels: &[&str], caption: impl Into<String>) {
        self.blocks.push(Block::Panels(
            file.into(),
            labels.iter().map(|l| l.to_string()).collect(),
            caption.into(),
        ));
    }
    /// Appends a [`Block::Markdown`].
    pub fn markdown(&mut self, s: impl Into<String>) {
        self.blocks.push(Block::Markdown(s.into()));
    }

    /// The relative file names of all figures.
    pub fn figures(&self) -> Vec<&str> {
        self.blocks
            .iter()
            .filter_map(|b| match b {
                Block::Figure(f, _) | Block::Panels(f, _, _) => Some(f.as_str()),
                _ => None,
            })
            .collect()
    }

    /// The document as one HTML page; figures are linked by file name, each image shown once.
    pub fn to_html(&self) -> String {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n\
             <style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;line-height:1.45}}\
             table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:3px 8px;text-align:right}}\
             th{{background:#eee}}td:first-child{{text-align:left}}img{{max-width:100%;border:1px solid #ddd}}\
             figure{{margin:1.5em 0}}figcaption{{color:#333;font-size:.95em;margin-top:.3em}}\
             .provenance td{{text-align:left}}pre{{background:#f4f4f4;padding:.6em;overflow-x:auto}}\
             .panel-labels{{display:flex;max-width:100%}}.panel-labels span{{flex:1;text-align:center;font-weight:bold}}\
             nav.toc ol{{columns:2}}</style></head><body>\n<h1>{}</h1>\n",
            esc(&self.title),
            esc(&self.title)
        );
        let headings: Vec<&String> = self
            .blocks
            .iter()
            .filter_map(|b| match b {
                Block::Heading(s) => Some(s),
                _ => None,
            })
            .collect();
        let mut k = 0;
        for b in &self.blocks {
            match b {
                Block::Heading(s) => {
                    let _ = writeln!(h, "<h2 id=\"{}\">{}</h2>", anchor(k), inline(s));
                    k += 1;
                }
                Block::Toc => {
                    h.push_str("<nav class=\"toc\"><h2>Contents</h2><ol>\n");
                    for (j, s) in headings.iter().enumerate() {
                        let _ =
                            writeln!(h, "<li><a href=\"#{}\">{}</a></li>", anchor(j), inline(s));
                    }
                    h.push_str("</ol></nav>\n");
                }
                Block::Panels(f, labels, c) => {
                    let _ = write!(h, "<figure><div class=\"panel-labels\">");
                    for l in labels {
                        let _ = write!(h, "<span>{}</span>", esc(l));
                    }
                    let _ = writeln!(
                        h,
                        "</div><a href=\"{f}\"><img src=\"{f}\" alt=\"{a}\"></a><figcaption>{c}</figcaption></figure>",
                        f = esc(f),
                        a = esc(&c.replace('`', "")),
                        c = inline(c)
                    );
                }
                Block::Paragraph(s) => {
                    let _ = writeln!(h, "<p>{}</p>", inline(s));
                }
                Block::Code(s) => {
                    let _ = writeln!(h, "<pre>{}</pre>", esc(s));
                }
                Block::Markdown(s) => h.push_str(&markdown_to_html(s)),
                Block::Figure(f, c) => {
                    let _ = writeln!(
                        h,
                        "<figure><a href=\"{f}\"><img src=\"{f}\" alt=\"{a}\"></a><figcaption>{c}</figcaption></figure>",
                        f = esc(f),
                        a = esc(&c.replace('`', "")),
                        c = inline(c)
                    );
                }
                Block::Table(head, rows) => {
                    h.push_str("<table><tr>");
                    for c in head {
                        let _ = write!(h, "<th>{}</th>", inline(c));
                    }
                    h.push_str("</tr>\n");
                    for r in rows {
                        h.push_str("<tr>");
                        for c in r {
                            let _ = write!(h, "<td>{}</td>", inline(c));
                        }
                        h.push_str("</tr>\n");
                    }
                    h.push_str("</table>\n");
                }
            }
        }
        h.push_str("</body></html>\n");
        embed_images_once(&h)
    }

    /// The document as Markdown.
    pub fn to_markdown(&self) -> String {
        let mut m = format!("# {}\n\n", self.title);
        for b in &self.blocks {
            match b {
                Block::Heading(s) => {
                    let _ = writeln!(m, "## {s}\n");
                }
                Block::Paragraph(s) => {
                    let _ = writeln!(m, "{s}\n");
                }
                Block::Code(s) => {
                    let _ = writeln!(m, "```\n{s}\n```\n");
                }
                Block::Markdown(s) => {
                    let _ = writeln!(m, "{}\n", demote_headings(s.trim()));
                }
                Block::Figure(f, c) => {
                    let _ = writeln!(m, "![{}]({f})\n\n*{c}*\n", md_cell(c));
                }
                Block::Panels(f, labels, c) => {
                    let _ = writeln!(
                        m,
                        "![{}]({f})\n\n*Panels, left to right: {}. {c}*\n",
                        md_cell(c),
                        labels.join(" | ")
                    );
                }
                Block::Toc => {
                    m.push_str("Contents:\n\n");
                    for b in &self.blocks {
                        if let Block::Heading(s) = b {
                            let _ = writeln!(m, "- {s}");
                        }
                    }
                    m.push('\n');
                }
                Block::Table(head, rows) => {
                    let _ = writeln!(
                        m,
                        "| {} |",
                        head.iter()
                            .map(|c| md_cell(c))
                            .collect::<Vec<_>>()
                            .join(" | ")
                    );
                    let _ = writeln!(m, "|{}", " --- |".repeat(head.len()));
                    for r in rows {
                        let _ = writeln!(
                            m,
                            "| {} |",
                            r.iter().map(|c| md_cell(c)).collect::<Vec<_>>().join(" | ")
                        );
                    }
                    m.push('\n');
                }
            }
        }
        m
    }

    /// Write `index.html` and `report.md` into folder `dir` of `out` (`.` for `out` itself; the
    /// folder holds the figures). The folder is created inside `out`; a symbolic link on the
    /// way is refused, never followed.
    pub fn write(&self, out: &OutDir, dir: &str) -> Result<()> {
        out.create_dir(dir)?;
        let name = |file: &str| match dir {
            "" | "." => file.to_string(),
            _ => format!("{dir}/{file}"),
        };
        out.write_text(&name("index.html"), &self.to_html())?;
        out.write_text(&name("report.md"), &self.to_markdown())?;
        Ok(())
    }
}

/// A sub-report's Markdown as HTML (CommonMark with tables, by pulldown-cmark), headings two
/// levels down so that they nest under the report's `<h2>` sections.
pub fn markdown_to_html(md: &str) -> String {
    use pulldown_cmark::{Event, HeadingLevel, Options, Parser, Tag, TagEnd};
    fn down(l: HeadingLevel) -> HeadingLevel {
        match l {
            HeadingLevel::H1 => HeadingLevel::H3,
            HeadingLevel::H2 => HeadingLevel::H4,
            HeadingLevel::H3 => HeadingLevel::H5,
            _ => HeadingLevel::H6,
        }
    }
    let events = Parser::new_ext(md, Options::ENABLE_TABLES).map(|e| match e {
        Event::Start(Tag::Heading {
            level,
            id,
            classes,
            attrs,
        }) => Event::Start(Tag::Heading {
            level: down(level),
            id,
            classes,
            attrs,
        }),
        Event::End(TagEnd::Heading(level)) => Event::End(TagEnd::Heading(down(level))),
        e => e,
    });
    let mut html = String::new();
    pulldown_cmark::html::push_html(&mut html, events);
    html
}

/// Markdown with every ATX heading two levels down (outside fenced code), as in
/// [`markdown_to_html`].
pub fn demote_headings(md: &str) -> String {
    let mut fenced = false;
    md.lines()
        .map(|l| {
            if l.trim_start().starts_with("```") {
                fenced = !fenced;
            }
            if !fenced && l.starts_with('#') {
                format!("##{l}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every `src="…"` / `href="…"` target in an HTML text (for checking a report's links).
pub fn html_references(html: &str) -> Vec<String> {
    let mut out = Vec::new();
    for key in ["src=\"", "href=\""] {
        let mut rest = html;
        while let Some(p) = rest.find(key) {
            rest = &rest[p + key.len()..];
            if let Some(e) = rest.find('"') {
                // in-page anchors (the table of contents) are not files
                if !rest.starts_with('#') {
                    out.push(rest[..e].replace("&amp;", "&"));
                }
                rest = &rest[e..];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_inside_its_folder_never_through_a_link() {
        let root = std::env::temp_dir().join(format!("momentlab-document-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let (out, outside) = (root.join("out"), root.join("outside"));
        std::fs::create_dir_all(&out).unwrap();
        std::fs::create_dir_all(&outside).unwrap();
        let od = OutDir::new(&out, true).unwrap();
        let d = Document::new("r");
        d.write(&od, ".").unwrap();
        d.write(&od, "sub").unwrap();
        for f in ["index.html", "report.md", "sub/index.html", "sub/report.md"] {
            assert!(out.join(f).is_file(), "{f}");
        }
        std::os::unix::fs::symlink(&outside, out.join("linked")).unwrap();
        let e = format!("{:#}", d.write(&od, "linked").unwrap_err());
        assert!(e.contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read_dir(&outside).unwrap().count(), 0);
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn html_and_markdown_escape_and_reference_figures() {
        let mut d = Document::new("A <b> report");
        d.paragraph("x < y & z");
        d.table(&["a", "b|c"], vec![vec!["1".into(), "2".into()]]);
        d.figure("fig.svg", "caption");
        let h = d.to_html();
        assert!(h.contains("A &lt;b&gt; report"));
        assert!(h.contains("x &lt; y &amp; z"));
        assert_eq!(
            html_references(&h),
            vec!["fig.svg".to_string(), "fig.svg".to_string()]
        );
        let m = d.to_markdown();
        assert!(m.contains("| a | b\\|c |"));
        assert!(m.contains("![caption](fig.svg)"));
        assert_eq!(d.figures(), vec!["fig.svg"]);
    }

    #[test]
    fn toc_panels_code_spans_and_each_image_once() {
        let mut d = Document::new("r");
        d.paragraph("run `momentlab tune`");
        d.toc();
        d.heading("First");
        d.figure("a.svg", "one");
        d.heading("Second");
        d.figure("a.svg", "again");
        d.panels(
            "eye/x.png",
            &["PCF", "vsm", "|vsm − PCF|"],
            "look for `leaks`",
        );
        let h = d.to_html();
        assert!(
            h.contains("<code>momentlab tune</code>") && !h.contains('`'),
            "{h}"
        );
        assert!(h.contains("<a href=\"#s0\">First</a>") && h.contains("<h2 id=\"s1\">Second</h2>"));
        assert_eq!(h.matches("<img src=\"a.svg\"").count(), 1, "{h}");
        assert!(h.contains("a.svg (shown above)"));
        assert!(h.contains("<span>PCF</span><span>vsm</span>"));
        assert_eq!(d.figures(), vec!["a.svg", "a.svg", "eye/x.png"]);
        let m = d.to_markdown();
        assert!(m.contains("- First\n- Second") && m.contains("Panels, left to right: PCF | vsm"));
    }

    #[test]
    fn markdown_blocks_become_html_tables_and_nested_headings() {
        let mut d = Document::new("r");
        d.markdown("# Sweep\n\n| a | b |\n|---:|---|\n| 1 | x < y |\n\n## Part\n\ntext *em*\n");
        let h = d.to_html();
        assert!(h.contains("<h3>Sweep</h3>"), "{h}");
        assert!(h.contains("<h4>Part</h4>"), "{h}");
        assert!(
            h.contains("<table>") && h.contains("<td>x &lt; y</td>"),
            "{h}"
        );
        assert!(h.contains("<em>em</em>"), "{h}");
        assert!(!h.contains("<pre>") && !h.contains("|---"), "{h}");
        let m = d.to_markdown();
        assert!(
            m.contains("### Sweep\n") && m.contains("#### Part\n"),
            "{m}"
        );
        assert_eq!(
            demote_headings("```\n# x\n```\n# y"),
            "```\n# x\n```\n### y"
        );
    }
}
