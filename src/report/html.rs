//! Self-contained HTML pages: plots are inlined (SVG as markup, PNG as a data
//! URI) and the style sheet is embedded, so a page opens from a laptop, an e-mail
//! attachment or a cluster's scratch folder with no network and no other file.
//!
//! Markup comes from `maud`, which escapes every interpolated string, so a clip
//! named `run<1>.mp4` cannot break a page.

use base64::Engine;
use maud::{DOCTYPE, Markup, PreEscaped, html};
use percent_encoding::{AsciiSet, NON_ALPHANUMERIC, utf8_percent_encode};

/// The style shared by every page: readable tables, figures that fit the window.
const STYLE: &str = "
body { font-family: 'DejaVu Sans', Arial, sans-serif; margin: 2em auto; max-width: 72em;
       padding: 0 1em; color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 0.5em 0 1em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th { background: #f2f2f2; } td.text, th.text { text-align: left; }
td.significant { background: #ffe1a8; font-weight: bold; }
td.bad, li.bad { color: #a40000; }
figure { margin: 1em 0; } figure svg, figure img, figure video { max-width: 100%; height: auto; }
button.frame { font-size: 0.85em; }
figcaption { color: #555; font-size: 0.9em; }
.note { color: #555; font-size: 0.9em; }
code { background: #f4f4f4; padding: 0 0.2em; }
";

/// A complete page: `title` as heading and window title, `body` below it.
pub fn page(title: &str, body: Markup) -> String {
    html! {
        (DOCTYPE)
        html lang="en" {
            head {
                meta charset="utf-8";
                meta name="viewport" content="width=device-width, initial-scale=1";
                title { (title) }
                style { (PreEscaped(STYLE)) }
            }
            body {
                h1 { (title) }
                (body)
            }
        }
    }
    .into_string()
}

/// An SVG document inlined as a figure. The XML prolog, which is not allowed
/// inside HTML, is dropped.
pub fn svg_figure(svg: &str, caption: &str) -> Markup {
    let start = svg.find("<svg").unwrap_or(0);
    html! {
        figure {
            (PreEscaped(&svg[start..]))
            figcaption { (caption) }
        }
    }
}

/// PNG bytes inlined as a figure through a data URI.
pub fn png_figure(png: &[u8], caption: &str) -> Markup {
    let data = base64::engine::general_purpose::STANDARD.encode(png);
    html! {
        figure {
            img src=(format!("data:image/png;base64,{data}")) alt=(caption);
            figcaption { (caption) }
        }
    }
}

/// A video in the page's folder (`src` relative to the page) as a figure, with
/// the element's `id` for scripts that seek it. Muted, so browsers allow it to
/// play without a click.
pub fn video_figure(src: &str, id: &str, caption: &str) -> Markup {
    html! {
        figure {
            video id=(id) src=(src) controls muted loop playsinline preload="auto" {}
            figcaption { (caption) }
        }
    }
}

/// A table with a header row; the first column is left-aligned text, the rest
/// right-aligned numbers. `highlight(row, column)` marks a cell (e.g. a
/// significant p-value).
pub fn table(
    header: &[&str],
    rows: &[Vec<String>],
    highlight: impl Fn(usize, usize) -> bool,
) -> Markup {
    linked_table(header, rows, &[], highlight)
}

/// [`table`] whose row `i` has its first cell link to `links[i]` (rows past the
/// end of `links` are not linked).
pub fn linked_table(
    header: &[&str],
    rows: &[Vec<String>],
    links: &[String],
    highlight: impl Fn(usize, usize) -> bool,
) -> Markup {
    html! {
        table {
            tr {
                @for (j, h) in header.iter().enumerate() {
                    th class=[(j == 0).then_some("text")] { (h) }
                }
            }
            @for (i, row) in rows.iter().enumerate() {
                tr {
                    @for (j, cell) in row.iter().enumerate() {
                        @let class = match (j == 0, highlight(i, j)) {
                            (true, _) => Some("text"),
                            (false, true) => Some("significant"),
                            (false, false) => None,
                        };
                        @match links.get(i).filter(|_| j == 0) {
                            Some(href) => td class=[class] { a href=(href) { (cell) } },
                            None => td class=[class] { (cell) },
                        }
                    }
                }
            }
        }
    }
}

/// Bytes a URL path keeps as they are: RFC 3986's unreserved set and `/`.
const URL_PATH_KEEPS: &AsciiSet = &NON_ALPHANUMERIC
    .remove(b'-')
    .remove(b'.')
    .remove(b'_')
    .remove(b'~')
    .remove(b'/');

/// A relative path as a URL path: every byte outside RFC 3986's unreserved set
/// (and `/`) percent-encoded, so a name with a space, `#`, `%`, `?` or any non-ASCII
/// letter links to its own file.
pub fn url_path(path: &str) -> String {
    utf8_percent_encode(path, URL_PATH_KEEPS).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use percent_encoding::percent_decode_str;

    /// A clip's path with every awkward character survives as a link: decoding the
    /// URL path gives the name back, and nothing in it ends the path early.
    #[test]
    fn a_url_path_decodes_to_the_name() {
        let name = "oak, old/say \"hi\"/ébène #1 100%?.mp4";
        let url = url_path(name);
        assert!(!url.contains([' ', '#', '?', '"', ',']), "{url}");
        assert_eq!(percent_decode_str(&url).decode_utf8().unwrap(), name);
    }

    #[test]
    fn text_is_escaped_and_svg_prolog_dropped() {
        let svg = "<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"></svg>";
        let body = html! {
            (svg_figure(svg, "a < b"))
            (table(&["clip", "n"], &[vec!["run<1>.mp4".into(), "0.5".into()]], |_, _| true))
        };
        let page = page("Study & results", body);
        assert!(page.starts_with("<!DOCTYPE html>"));
        assert!(page.contains("Study &amp; results"));
        assert!(page.contains("run&lt;1&gt;.mp4"));
        assert!(page.contains("a &lt; b"));
        assert!(!page.contains("<?xml"));
        assert!(page.contains("class=\"significant\">0.5"));
    }

    #[test]
    fn png_is_inlined_as_a_data_uri() {
        let figure = png_figure(&[0x89, b'P', b'N', b'G'], "frame").into_string();
        assert!(
            figure.contains("src=\"data:image/png;base64,iVBORw==\""),
            "{figure}"
        );
    }
}
