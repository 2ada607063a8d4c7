//! Text into HTML: what the report pages (`sweep_report`, `overview`) share.

/// `text` with `&`, `<`, `>` and `"` escaped, for element content and quoted attributes.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
