//! Errors in model files: each names the file, the place (line and column where it can be
//! found, and the path inside the model), what is wrong, and the fix.

use super::spans::Spans;
use std::fmt;
use std::ops::Range;
use std::sync::Arc;

/// The classes of bad input, so callers and tests can tell them apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file could not be read.
    Io,
    /// Malformed RON, or a field of the wrong type, missing or unknown.
    Syntax,
    /// A syntax error inside an expression string.
    ExpressionSyntax,
    /// A name in an expression that is not a parameter, coordinate, function or `t`.
    UnknownName,
    /// A vector or matrix with the wrong number of entries.
    Dimension,
    /// A reference to a frame or body that does not exist.
    UnknownFrame,
    /// The frame tree has a cycle.
    FrameCycle,
    /// Time functions that call each other in a cycle.
    Cycle,
    /// A name used twice.
    Duplicate,
    /// A mass that is not positive.
    NonPositiveMass,
    /// An inertia matrix that is not symmetric positive semi-definite.
    InertiaNotPsd,
    /// A velocity constraint that is not linear in the velocities, or a position constraint
    /// that uses velocities.
    NonlinearConstraint,
    /// Too many or too few quasi-velocities.
    QuasiVelocityCount,
    /// A declared ignorable coordinate that fails Definition 1.
    NotIgnorable,
    /// A choice of quasi-velocities (with the constraints) that does not determine `q'`.
    SingularQuasiVelocities,
    /// Initial values missing, or initial velocities that violate the constraints.
    InitialState,
    /// A parameter value that is not a finite number, or another bad value.
    BadValue,
    /// Ignorable coordinates asked to leave the state while the equations depend on them.
    IgnorableNeeded,
    /// The derived equations could not be emitted as Rust (a number that is not a finite
    /// float, or a function left without a definition).
    Emission,
    /// The derivation needs more work than its budget allows (the model is too large).
    Budget,
}

/// A located error in a model file.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelError {
    pub kind: ErrorKind,
    /// The file as given by the user, its control characters escaped ([`files::printable`]).
    pub file: String,
    /// 1-based line and column, when the place could be found in the file.
    pub location: Option<(usize, usize)>,
    /// The path inside the model, e.g. `bodies[1] (bar1).com[0]`.
    pub place: String,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub help: String,
    /// The bytes of the file the error is about, when known.
    pub span: Option<Range<usize>>,
    /// The file's text, for a labelled excerpt (see [`ModelError::render`]).
    pub source_text: Option<Arc<str>>,
}

impl ModelError {
    /// An error about `span` of `source`; the line and column come from the span.
    pub fn at(kind: ErrorKind, file: &str, source: &str, span: Option<Range<usize>>, place: &str, message: String, help: String) -> ModelError {
        ModelError {
            kind,
            file: files::printable(file),
            location: span.as_ref().map(|r| line_col(source, r.start)),
            place: shorten(&files::printable(place), 2 * MAX_QUOTED_CHARS),
            message: printable_text(&message),
            help: printable_text(&help),
            span,
            source_text: Some(Arc::from(source)),
        }
    }

    /// An error at `place` in a model that has no text of its own to point into (a URDF robot's,
    /// whose model is made from the XML): the file and the place are named, with no line.
    pub fn in_place(kind: ErrorKind, file: &str, place: &str, message: String, help: String) -> ModelError {
        ModelError { place: shorten(&files::printable(place), 2 * MAX_QUOTED_CHARS), ..ModelError::unlocated(kind, file, message, help) }
    }

    /// An error with no place in a file (the file cannot be read, for instance).
    pub fn unlocated(kind: ErrorKind, file: &str, message: String, help: String) -> ModelError {
        ModelError {
            kind,
            file: files::printable(file),
            location: None,
            place: String::new(),
            message: printable_text(&message),
            help: printable_text(&help),
            span: None,
            source_text: None,
        }
    }
}

/// A message with the control characters a user's text may have brought in escaped (a name, an
/// expression, a path), its own line breaks kept: nothing in an error moves a terminal's cursor
/// or colours it.
/// A word of an error (a name, an expression, a path the user gave) longer than this is shortened.
const MAX_QUOTED_CHARS: usize = 80;

fn printable_text(text: &str) -> String {
    shorten_words(&text.split('\n').map(files::printable).collect::<Vec<_>>().join("\n"))
}

/// `text` cut to its start and end around an ellipsis when it has more than `max` characters.
fn shorten(text: &str, max: usize) -> String {
    let chars = text.chars().count();
    if chars <= max {
        return text.to_string();
    }
    let (head, tail) = (max * 3 / 4, max / 4);
    text.chars().take(head).chain(std::iter::once('…')).chain(text.chars().skip(chars - tail)).collect()
}

/// `text` with each word (a run without spaces) over `MAX_QUOTED_CHARS` cut to its start
/// and end around an ellipsis: a name or expression of thousands of characters is quoted, not
/// copied, whatever quotes it.
pub fn shorten_words(text: &str) -> String {
    text.split(' ').map(|word| shorten(word, MAX_QUOTED_CHARS)).collect::<Vec<_>>().join(" ")
}

impl ModelError {
    /// The error as a report with a labelled excerpt of the file and the fix (rendered by
    /// miette), in colour when `color` (a terminal); without a place in a text, the one-line
    /// form of `Display`.
    ///
    /// ```
    /// let src = "Model(\n  name: \"m\",\n  typo: 3,\n)";
    /// let e = generator::model::from_source("m.ron", src).unwrap_err();
    /// let report = e.render(false);
    /// assert!(report.contains("m.ron:3:3") && report.contains("typo: 3") && report.contains("help:"), "{report}");
    /// ```
    pub fn render(&self, color: bool) -> String {
        let (Some(text), Some(span)) = (&self.source_text, &self.span) else { return self.to_string() };
        let start = floor_char_boundary(text, span.start.min(text.len()));
        let end = floor_char_boundary(text, span.end.clamp(start, text.len()));
        let (window, span) = Window::around(&self.file, text, start..end);
        let excerpt = Excerpt { error: self, source: window, span: (span.start, span.len()).into() };
        let theme = if color { miette::GraphicalTheme::unicode() } else { miette::GraphicalTheme::unicode_nocolor() };
        let handler = miette::GraphicalReportHandler::new_themed(theme).with_wrap_lines(false).with_context_lines(1);
        let mut out = String::new();
        match handler.render_report(&mut out, &excerpt) {
            Ok(()) => format!("error: {}", out.trim_start().trim_start_matches('×').trim_start()),
            Err(_) => self.to_string(),
        }
    }
}

/// The widest line an excerpt shows whole, in characters: a longer one (a model written on one
/// line by a script) is shown as this many characters around the error's column. (The
/// renderer pads to the column, and a padding past 65535 is a panic in Rust's formatting.)
const WIDEST_LINE: usize = 160;

/// The largest char boundary of `text` at or before `at`.
fn floor_char_boundary(text: &str, at: usize) -> usize {
    (0..=at.min(text.len())).rev().find(|&i| text.is_char_boundary(i)).unwrap_or(0)
}

/// The part of a file an excerpt shows: the error's line and one line either side, each cut to
/// [`WIDEST_LINE`] characters around the error's column (marked `…` where cut), numbered as
/// in the file.
#[derive(Debug)]
struct Window {
    name: String,
    text: String,
    /// The file's 0-based line number of the window's first line.
    first_line: usize,
    /// The bytes of the error's line before the band shown, less those of the `…` that stands
    /// for them: added to the column the renderer names (it counts bytes).
    column_shift: usize,
}

impl Window {
    /// The window of `text` around `span`, and the span's place in it.
    fn around(name: &str, text: &str, span: Range<usize>) -> (Window, Range<usize>) {
        let line_start = |at: usize| text[..at].rfind('\n').map_or(0, |i| i + 1);
        let line_end = |at: usize| text[at..].find('\n').map_or(text.len(), |i| at + i);
        let (err_start, err_end) = (line_start(span.start), line_end(span.start));
        let first = if err_start == 0 { 0 } else { line_start(err_start - 1) };
        let last = if err_end == text.len() { err_end } else { line_end(err_end + 1) };
        let lines: Vec<(usize, &str)> = {
            let mut at = first;
            text[first..last]
                .split('\n')
                .map(|l| {
                    let offset = at;
                    at += l.len() + 1;
                    (offset, l)
                })
                .collect()
        };
        let whole = Window { name: name.to_string(), text: text.to_string(), first_line: 0, column_shift: 0 };
        if lines.iter().all(|(_, l)| l.chars().count() <= WIDEST_LINE) {
            return (whole, span);
        }
        // The characters shown of every line: a band of columns around the error's.
        let column = text[err_start..span.start].chars().count();
        let from = column.saturating_sub(WIDEST_LINE / 2);
        let to = from + WIDEST_LINE;
        let mut out = String::new();
        let mut placed = 0..0;
        let mut column_shift = 0;
        for (k, (offset, line)) in lines.iter().enumerate() {
            if k > 0 {
                out.push('\n');
            }
            let chars: Vec<(usize, char)> = line.char_indices().collect();
            let cut_before = from > 0 && chars.len() > from;
            if cut_before {
                out.push('…');
            }
            let band_start = chars.get(from).map_or(line.len(), |(i, _)| *i);
            let band_end = chars.get(to).map_or(line.len(), |(i, _)| *i);
            let shown_from = out.len();
            out.push_str(&line[band_start.min(band_end)..band_end]);
            if band_end < line.len() {
                out.push('…');
            }
            if *offset == err_start {
                column_shift = if cut_before { band_start - '…'.len_utf8() } else { 0 };
                // The span, clipped to the band shown.
                let local = |at: usize| (at - offset).clamp(band_start, band_end) - band_start + shown_from;
                placed = local(span.start)..local(span.end.min(offset + line.len()));
            }
        }
        let first_line = text[..first].matches('\n').count();
        (Window { name: name.to_string(), text: out, first_line, column_shift }, placed)
    }
}

impl miette::SourceCode for Window {
    fn read_span<'a>(&'a self, span: &miette::SourceSpan, before: usize, after: usize) -> Result<Box<dyn miette::SpanContents<'a> + 'a>, miette::MietteError> {
        let inner = self.text.as_str().read_span(span, before, after)?;
        Ok(Box::new(miette::MietteSpanContents::new_named(
            self.name.clone(),
            inner.data(),
            *inner.span(),
            inner.line() + self.first_line,
            // The renderer reads the primary label alone (no context lines) for the column it
            // names; the context it draws starts each line at column 0 of the band.
            inner.column() + if before == 0 && after == 0 { self.column_shift } else { 0 },
            inner.line_count(),
        )))
    }
}

/// A [`ModelError`] as a miette diagnostic: its header, the labelled span, the fix.
#[derive(Debug)]
struct Excerpt<'a> {
    error: &'a ModelError,
    source: Window,
    span: miette::SourceSpan,
}

impl fmt::Display for Excerpt<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = self.error;
        write!(f, "{}", e.file)?;
        if let Some((l, c)) = e.location {
            write!(f, ":{l}:{c}")?;
        }
        if !e.place.is_empty() {
            write!(f, ": in {}", e.place)?;
        }
        write!(f, ": {}", e.message)
    }
}

impl std::error::Error for Excerpt<'_> {}

impl miette::Diagnostic for Excerpt<'_> {
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        (!self.error.help.is_empty()).then(|| Box::new(&self.error.help) as Box<dyn fmt::Display>)
    }
    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        Some(&self.source)
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        let label = if self.error.place.is_empty() { "here".to_string() } else { self.error.place.clone() };
        Some(Box::new(std::iter::once(miette::LabeledSpan::new_with_span(Some(label), self.span))))
    }
}

/// The bytes an error at `place` is about: the value at that path in the file (or its deepest
/// enclosing value), narrowed to the first occurrence of `needle` inside it when there is one;
/// without a path that resolves, the first occurrence of `needle` in the file.
pub fn place_span(source: &str, spans: &Spans, place: &str, needle: &str) -> Option<Range<usize>> {
    match spans.find(place) {
        Some(r) => {
            if !needle.is_empty()
                && let Some(i) = source.get(r.clone()).and_then(|text| text.find(needle))
            {
                return Some(r.start + i..r.start + i + needle.len());
            }
            Some(r)
        }
        None if !needle.is_empty() => source.find(needle).map(|i| i..i + needle.len()),
        None => None,
    }
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "error: {}", self.file)?;
        if let Some((l, c)) = self.location {
            write!(f, ":{l}:{c}")?;
        }
        if !self.place.is_empty() {
            write!(f, ": in {}", self.place)?;
        }
        write!(f, ": {}", self.message)?;
        if !self.help.is_empty() {
            write!(f, "\n  help: {}", self.help)?;
        }
        Ok(())
    }
}

impl std::error::Error for ModelError {}

/// 1-based line and column of a byte offset.
pub fn line_col(source: &str, idx: usize) -> (usize, usize) {
    let before = &source[..idx.min(source.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(before.len(), |p| before.len() - p - 1) + 1;
    (line, col)
}

/// The candidate closest to `name` by edit distance, if any is close.
///
/// The same name in another case wins over every other candidate (`L` for `l`, not `M`).
pub fn closest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let candidates: Vec<&'a str> = candidates.into_iter().collect();
    if let Some(same) = candidates.iter().find(|c| c.eq_ignore_ascii_case(name)) {
        return Some(same);
    }
    candidates.into_iter().map(|c| (edit_distance(name, c), c)).filter(|(d, c)| *d <= 2.max(c.len() / 3)).min().map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            cur.push((prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1));
        }
        prev = cur;
    }
    prev[b.len()]
}

/// At most 60 characters of an expression around `column` (1-based), with `…` where cut, so
/// that an error about a 20,000-character input stays one readable line.
pub fn excerpt(src: &str, column: usize) -> String {
    const WIDTH: usize = 60;
    let chars: Vec<char> = src.chars().collect();
    if chars.len() <= WIDTH {
        return src.to_string();
    }
    let start = column.saturating_sub(1 + WIDTH / 2).min(chars.len() - WIDTH);
    let end = start + WIDTH;
    let mut out = String::new();
    if start > 0 {
        out.push('…');
    }
    out.extend(&chars[start..end]);
    if end < chars.len() {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_and_suggests() {
        let src = "a: \"x\",\nb: \"l/2\",\n";
        assert_eq!(line_col(src, src.find("\"l/2\"").unwrap()), (2, 4));
        assert_eq!(closest("thta1", ["theta1", "theta2", "x"]), Some("theta1"));
        assert_eq!(closest("zzz", ["theta1"]), None);
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn shorten_words_example() {
        use crate::model::error::shorten_words;
        let long = format!("`{}` is not a name", "x".repeat(500));
        let short = shorten_words(&long);
        assert!(short.len() < 120 && short.ends_with("` is not a name") && short.contains('…'), "{short}");
        assert_eq!(shorten_words("`ok` is fine"), "`ok` is fine");
    }

    #[test]
    fn place_span_example() {
        use crate::model::{error::place_span, spans::Spans};
        let src = "Model(bodies: [Body(mass: \"0\"), Body(mass: \"0\")])";
        let r = place_span(src, &Spans::new(src), "bodies[1] (b).mass", "\"0\"").unwrap();
        assert_eq!(r.start, src.rfind("\"0\"").unwrap());
    }

    #[test]
    fn excerpt_example() {
        use crate::model::error::excerpt;
        assert_eq!(excerpt("l*cos(q)", 3), "l*cos(q)");
        let long = format!("{}x{}", "sin(".repeat(300), ")".repeat(300));
        let cut = excerpt(&long, 804);
        assert!(cut.starts_with('…') && cut.ends_with('…') && cut.chars().count() <= 62, "{cut}");
    }
}
