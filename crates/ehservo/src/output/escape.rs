//! Escaping text for the documents the program writes: HTML (the league's
//! and the reproduction's reports), XML (an FMU's `modelDescription.xml`)
//! and Markdown table cells (the reports, the generated reference pages).
//! One place, so that every writer escapes the same characters.

/// Text safe inside an HTML or XML element and inside a double-quoted
/// attribute value: `&`, `<`, `>` and `"` as entities.
pub fn html(s: &str) -> String {
    html_text(s).replace('"', "&quot;")
}

/// Text safe inside an HTML element (not inside an attribute value: `"`
/// is left as it is): `&`, `<` and `>` as entities.
pub fn html_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Text as one Markdown table cell: `|` escaped, a line break made a
/// space (a cell is one line).
pub fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Text as inline code in a Markdown table cell: in backticks, with
/// [`md_cell`]'s escaping (a table's `|` ends a cell even in code).
pub fn md_code(s: &str) -> String {
    format!("`{}`", md_cell(s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn html_escapes_markup_and_quotes() {
        assert_eq!(
            html(r#"a < b && c > "d" 'e'"#),
            "a &lt; b &amp;&amp; c &gt; &quot;d&quot; 'e'"
        );
        // An entity already in the text is escaped again: text, not markup.
        assert_eq!(html("&amp;"), "&amp;amp;");
        assert_eq!(html("θ̈ (rad/s²)"), "θ̈ (rad/s²)");
    }

    #[test]
    fn html_text_leaves_quotes() {
        assert_eq!(
            html_text(r#"<b>"x" & y</b>"#),
            r#"&lt;b&gt;"x" &amp; y&lt;/b&gt;"#
        );
    }

    #[test]
    fn md_cell_escapes_pipes_and_joins_lines() {
        assert_eq!(md_cell("a | b\nc"), r"a \| b c");
        assert_eq!(md_cell("`x`"), "`x`");
        assert_eq!(md_code("a|b"), r"`a\|b`");
        assert_eq!(md_code("[1, 2]"), "`[1, 2]`");
    }
}
