//! A small document model written out as Markdown and as self-contained
//! HTML (figures embedded), so both reports say the same thing.

use crate::output::escape::{html, html_text, md_cell};
use base64::Engine;
use std::fmt::Write;

/// A block of the report.
#[derive(Debug, Clone)]
pub enum Block {
    /// Heading of a level (1..=3).
    Heading(u8, String),
    /// A paragraph (Markdown inline syntax: `code`, **bold**, links are kept as text in HTML).
    Para(String),
    /// A bullet list.
    List(Vec<String>),
    /// A table: header and rows.
    Table(Vec<String>, Vec<Vec<String>>),
    /// A figure: relative path of the PNG, caption.
    Figure(String, String),
}

/// A document.
#[derive(Debug, Clone, Default)]
pub struct Doc {
    /// The blocks, in order.
    pub blocks: Vec<Block>,
}

/// `code` → <code>, **x** → <b>, after escaping.
fn html_inline(s: &str) -> String {
    let e = html_text(s);
    let mut out = String::new();
    let mut code = false;
    for (i, part) in e.split('`').enumerate() {
        if i > 0 {
            out.push_str(if code { "</code>" } else { "<code>" });
            code = !code;
        }
        if code {
            out.push_str(part);
        } else {
            let mut bold = false;
            for (j, p) in part.split("**").enumerate() {
                if j > 0 {
                    out.push_str(if bold { "</b>" } else { "<b>" });
                    bold = !bold;
                }
                out.push_str(p);
            }
            if bold {
                out.push_str("</b>");
            }
        }
    }
    if code {
        out.push_str("</code>");
    }
    out
}

impl Doc {
    /// Adds a block.
    pub fn push(&mut self, b: Block) {
        self.blocks.push(b);
    }

    /// Markdown.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        for b in &self.blocks {
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(s, "{} {t}\n", "#".repeat(*l as usize));
                }
                Block::Para(t) => {
                    let _ = writeln!(s, "{t}\n");
                }
                Block::List(items) => {
                    for i in items {
                        let _ = writeln!(s, "- {i}");
                    }
                    s.push('\n');
                }
                Block::Table(head, rows) => {
                    let _ = writeln!(
                        s,
                        "| {} |",
                        head.iter()
                            .map(|h| md_cell(h))
                            .collect::<Vec<_>>()
                            .join(" | ")
                    );
                    let _ = writeln!(
                        s,
                        "|{}|",
                        head.iter().map(|_| "---").collect::<Vec<_>>().join("|")
                    );
                    for r in rows {
                        let _ = writeln!(
                            s,
                            "| {} |",
                            r.iter().map(|c| md_cell(c)).collect::<Vec<_>>().join(" | ")
                        );
                    }
                    s.push('\n');
                }
                Block::Figure(path, caption) => {
                    let _ = writeln!(s, "![{}]({path})\n\n*{caption}*\n", md_cell(caption));
                }
            }
        }
        s
    }

    /// Self-contained HTML; figures are read from `base` and embedded.
    pub fn to_html(&self, title: &str, base: &std::path::Path) -> String {
        let mut s = String::new();
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
body{{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;line-height:1.45;color:#222}}\
table{{border-collapse:collapse;margin:1em 0;font-size:0.92em}}th,td{{border:1px solid #ccc;padding:4px 8px;vertical-align:top}}\
th{{background:#f3f3f3}}td.agree{{background:#e6f4e6}}td.differ{{background:#fbe6e6}}td.undetermined,td.undecided{{background:#f5f0dc}}\
figure{{margin:1.5em 0}}figure img{{max-width:100%;border:1px solid #ddd}}figcaption{{font-style:italic;color:#444}}\
code{{background:#f4f4f4;padding:0 3px}}</style></head><body>\n",
            html_text(title)
        );
        for b in &self.blocks {
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(s, "<h{l}>{}</h{l}>", html_inline(t));
                }
                Block::Para(t) => {
                    let _ = writeln!(s, "<p>{}</p>", html_inline(t));
                }
                Block::List(items) => {
                    s.push_str("<ul>\n");
                    for i in items {
                        let _ = writeln!(s, "<li>{}</li>", html_inline(i));
                    }
                    s.push_str("</ul>\n");
                }
                Block::Table(head, rows) => {
                    s.push_str("<table><thead><tr>");
                    for h in head {
                        let _ = write!(s, "<th>{}</th>", html_inline(h));
                    }
                    s.push_str("</tr></thead><tbody>\n");
                    for r in rows {
                        s.push_str("<tr>");
                        for c in r {
                            let class = match c.as_str() {
                                "agree" | "differ" | "undetermined" | "undecided" => {
                                    format!(" class=\"{c}\"")
                                }
                                _ => String::new(),
                            };
                            let _ = write!(s, "<td{class}>{}</td>", html_inline(c));
                        }
                        s.push_str("</tr>\n");
                    }
                    s.push_str("</tbody></table>\n");
                }
                Block::Figure(path, caption) => {
                    let src = match std::fs::read(base.join(path)) {
                        Ok(bytes) => format!(
                            "data:image/png;base64,{}",
                            base64::engine::general_purpose::STANDARD.encode(bytes)
                        ),
                        Err(_) => html(path),
                    };
                    let _ = writeln!(
                        s,
                        "<figure><img src=\"{src}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
                        html(caption),
                        html_inline(caption)
                    );
                }
            }
        }
        s.push_str("</body></html>\n");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inline_markup_and_escaping() {
        assert_eq!(
            html_inline("a `x<y` **b**"),
            "a <code>x&lt;y</code> <b>b</b>"
        );
        let mut d = Doc::default();
        d.push(Block::Table(vec!["a|b".into()], vec![vec!["agree".into()]]));
        assert!(d.to_markdown().contains("a\\|b"));
        assert!(d
            .to_html("t", std::path::Path::new("."))
            .contains("class=\"agree\""));
    }
}
