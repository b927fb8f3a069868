//! Where each value of a model file is: a small scanner over the RON text that records the
//! byte span of every value under its path (`bodies[1].com[0]`, `forces[1].components.theta1`),
//! so that an error is reported at the value it is about, not at the first occurrence of some
//! text. Serde does not give spans; the scanner runs only when an error is reported.

use std::collections::HashMap;
use std::ops::Range;

/// The span of every value of a RON text, by path.
#[derive(Clone, Debug, Default)]
pub struct Spans {
    by_path: HashMap<String, Range<usize>>,
}

/// Deeper than this, the scanner stops (the RON parser refuses such files anyway).
const MAX_DEPTH: usize = 256;

impl Spans {
    /// Scans `source`; what cannot be scanned (a syntax error) is simply not recorded.
    pub fn new(source: &str) -> Spans {
        let mut s = Scanner { src: source.as_bytes(), at: 0, spans: Spans::default() };
        s.value(String::new(), 0);
        s.spans
    }

    /// The span of the value at `place`, a path as errors name it (`bodies[1] (bar1).com[0]`:
    /// the parenthesized names are decoration), or of its deepest enclosing value that exists.
    pub fn find(&self, place: &str) -> Option<Range<usize>> {
        let path = normalize(place);
        let mut cut = path.as_str();
        loop {
            if let Some(r) = self.by_path.get(cut) {
                return Some(r.clone());
            }
            let shorter = cut.rfind(['.', '[']).map(|i| &cut[..i])?;
            if shorter.is_empty() {
                return None;
            }
            cut = shorter;
        }
    }

    /// The path of the innermost value that holds byte `at` (ties: the shortest path).
    pub fn path_at(&self, at: usize) -> Option<String> {
        self.by_path.iter().filter(|(p, r)| r.contains(&at) && !p.is_empty()).min_by_key(|(p, r)| (r.len(), p.len(), p.as_str())).map(|(p, _)| p.clone())
    }

    /// The exact path only.
    pub fn get(&self, path: &str) -> Option<Range<usize>> {
        self.by_path.get(&normalize(path)).cloned()
    }
}

/// `bodies[1] (bar1).com[0]` -> `bodies[1].com[0]`.
fn normalize(place: &str) -> String {
    let mut out = String::with_capacity(place.len());
    let mut depth = 0usize;
    let chars: Vec<char> = place.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        match chars[i] {
            ' ' if chars.get(i + 1) == Some(&'(') => {
                depth += 1;
                i += 2;
                continue;
            }
            '(' if depth > 0 => depth += 1,
            ')' if depth > 0 => depth -= 1,
            c if depth == 0 => out.push(c),
            _ => {}
        }
        i += 1;
    }
    out
}

struct Scanner<'a> {
    src: &'a [u8],
    at: usize,
    spans: Spans,
}

impl Scanner<'_> {
    fn peek(&self) -> Option<u8> {
        self.src.get(self.at).copied()
    }

    /// Skips whitespace and comments.
    fn skip(&mut self) {
        loop {
            match self.peek() {
                Some(b) if b.is_ascii_whitespace() => self.at += 1,
                Some(b'/') if self.src.get(self.at + 1) == Some(&b'/') => {
                    while let Some(b) = self.peek() {
                        self.at += 1;
                        if b == b'\n' {
                            break;
                        }
                    }
                }
                Some(b'/') if self.src.get(self.at + 1) == Some(&b'*') => {
                    self.at += 2;
                    while self.at < self.src.len() && !(self.src[self.at] == b'*' && self.src.get(self.at + 1) == Some(&b'/')) {
                        self.at += 1;
                    }
                    self.at = (self.at + 2).min(self.src.len());
                }
                _ => return,
            }
        }
    }

    fn eat(&mut self, b: u8) -> bool {
        self.skip();
        if self.peek() == Some(b) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn ident(&mut self) -> Option<String> {
        self.skip();
        let start = self.at;
        while let Some(b) = self.peek() {
            if b.is_ascii_alphanumeric() || b == b'_' || b >= 0x80 {
                self.at += 1;
            } else {
                break;
            }
        }
        (self.at > start).then(|| String::from_utf8_lossy(&self.src[start..self.at]).into_owned())
    }

    /// A string literal's content (escapes kept as written), the scanner after its quote.
    fn string(&mut self) -> String {
        let start = self.at + 1;
        self.at += 1;
        while let Some(b) = self.peek() {
            self.at += 1;
            match b {
                b'\\' => self.at += 1,
                b'"' => return String::from_utf8_lossy(&self.src[start..self.at - 1]).into_owned(),
                _ => {}
            }
        }
        String::from_utf8_lossy(&self.src[start.min(self.src.len())..]).into_owned()
    }

    /// True when the parenthesized items from here hold one item (a trailing comma allowed):
    /// a look ahead over balanced brackets and strings, the scanner left where it was.
    fn single_item(&self) -> bool {
        let mut depth = 0usize;
        let mut i = self.at;
        let mut seen_comma = false;
        while let Some(&b) = self.src.get(i) {
            match b {
                b'"' => {
                    i += 1;
                    while let Some(&c) = self.src.get(i) {
                        if c == b'\\' {
                            i += 1;
                        } else if c == b'"' {
                            break;
                        }
                        i += 1;
                    }
                }
                b'(' | b'[' | b'{' => depth += 1,
                b')' | b']' | b'}' if depth == 0 => return true,
                b')' | b']' | b'}' => depth -= 1,
                b',' if depth == 0 => seen_comma = true,
                b if seen_comma && !b.is_ascii_whitespace() => return false,
                _ => {}
            }
            i += 1;
        }
        true
    }

    fn record(&mut self, path: &str, span: Range<usize>) {
        self.spans.by_path.entry(path.to_string()).or_insert(span);
    }

    /// One value at `path`; returns whether one was found.
    fn value(&mut self, path: String, depth: usize) -> bool {
        if depth > MAX_DEPTH {
            return false;
        }
        self.skip();
        let start = self.at;
        match self.peek() {
            None => false,
            Some(b'"') => {
                self.string();
                self.record(&path, start..self.at);
                true
            }
            Some(b'[') => {
                self.at += 1;
                let mut i = 0;
                loop {
                    if self.eat(b']') {
                        break;
                    }
                    if !self.value(format!("{path}[{i}]"), depth + 1) {
                        return false;
                    }
                    i += 1;
                    if self.eat(b',') {
                        continue;
                    }
                    if self.eat(b']') {
                        break;
                    }
                    return false;
                }
                self.record(&path, start..self.at);
                true
            }
            Some(b'{') => {
                self.at += 1;
                loop {
                    self.skip();
                    if self.eat(b'}') {
                        break;
                    }
                    let key = if self.peek() == Some(b'"') { self.string() } else { self.ident().unwrap_or_default() };
                    if !self.eat(b':') {
                        return false;
                    }
                    let child = if path.is_empty() { key } else { format!("{path}.{key}") };
                    if !self.value(child, depth + 1) {
                        return false;
                    }
                    if !self.eat(b',') {
                        if self.eat(b'}') {
                            break;
                        }
                        return false;
                    }
                }
                self.record(&path, start..self.at);
                true
            }
            Some(b'(') => self.parenthesized(path, start, depth),
            Some(b) if b.is_ascii_alphabetic() || b == b'_' => {
                self.ident();
                self.skip();
                if self.peek() == Some(b'(') {
                    self.parenthesized(path, start, depth)
                } else {
                    self.record(&path, start..self.at);
                    true
                }
            }
            Some(_) => {
                // A number, a char, or something the RON parser refused: up to a delimiter.
                while let Some(b) = self.peek() {
                    if matches!(b, b',' | b')' | b']' | b'}') || b.is_ascii_whitespace() {
                        break;
                    }
                    self.at += 1;
                }
                self.record(&path, start..self.at);
                self.at > start
            }
        }
    }

    /// `(field: value, ...)` or `(item, ...)`, the scanner at `(`. A tuple of one item is
    /// transparent: `Z("q")` and `Diagonal([...])` take their parent's path; the items of a
    /// longer one are `[i]`.
    fn parenthesized(&mut self, path: String, start: usize, depth: usize) -> bool {
        self.at += 1;
        // Named fields?
        let save = self.at;
        let named = self.ident().is_some() && self.eat(b':');
        self.at = save;
        if named {
            loop {
                if self.eat(b')') {
                    break;
                }
                let Some(field) = self.ident() else { return false };
                if !self.eat(b':') {
                    return false;
                }
                let child = if path.is_empty() { field } else { format!("{path}.{field}") };
                if !self.value(child, depth + 1) {
                    return false;
                }
                if !self.eat(b',') {
                    if self.eat(b')') {
                        break;
                    }
                    return false;
                }
            }
        } else {
            let single = self.single_item();
            let mut i = 0;
            loop {
                if self.eat(b')') {
                    break;
                }
                let child = if single { path.clone() } else { format!("{path}[{i}]") };
                if !self.value(child, depth + 1) {
                    return false;
                }
                i += 1;
                if !self.eat(b',') {
                    if self.eat(b')') {
                        break;
                    }
                    return false;
                }
            }
        }
        self.record(&path, start..self.at);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_model_files_are_indexed_to_their_leaves() {
        let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
        let spans = Spans::new(&src);
        let at = |p: &str| &src[spans.get(p).unwrap_or_else(|| panic!("{p}"))];
        assert_eq!(at("name"), "\"cart_pendulum\"");
        assert_eq!(at("parameters.tau"), "0.0");
        assert_eq!(at("frames[2].rotation[0]"), "\"theta2 - theta1\"");
        assert_eq!(at("bodies[2].inertia[2]"), "\"m2*l^2/12\"");
        assert_eq!(at("forces[1].components.theta2"), "\"-tau\"");
        assert_eq!(at("constraints[0].expr"), "\"l*cos(theta1 - theta2)*theta1' + l*theta2'\"");
        assert_eq!(at("quasi_velocities.reduced[0]"), "\"theta2' - theta1'\"");
        assert_eq!(at("initial.qdot.theta2"), "\"-cos(theta1 - theta2)*theta1'\"");
        assert_eq!(at("ignorable"), "[\"x\"]");
        assert_eq!(at("ignorable[0]"), "\"x\"");
        // A missing leaf falls back to its deepest existing parent.
        assert_eq!(spans.find("bodies[1] (bar1).com[7]"), spans.get("bodies[1].com"));
        assert_eq!(spans.find("nothing.here"), None);
    }

    #[test]
    fn broken_text_is_indexed_as_far_as_it_goes() {
        let spans = Spans::new("Model(name: \"x\", bodies: [Body(mass: ");
        assert!(spans.get("name").is_some());
        assert!(spans.get("bodies[0].mass").is_none());
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::model::spans::Spans;
        let src = "Model(name: \"m\", bodies: [Body(mass: \"0\"), Body(mass: \"0\", com: [\"1\", \"2\"])])";
        let spans = Spans::new(src);
        let second = spans.find("bodies[1] (b2).mass").unwrap();
        assert_eq!(&src[second.clone()], "\"0\"");
        assert!(second.start > src.find("Body(mass: \"0\", com").unwrap());
        assert_eq!(&src[spans.find("bodies[1].com[1]").unwrap()], "\"2\"");
    }

    #[test]
    fn path_at_example() {
        let src = "Model(bodies: [Body(com: [\"0\", \"-l/2*1e200\"])])";
        let at = src.find("1e200").unwrap();
        assert_eq!(crate::model::spans::Spans::new(src).path_at(at).as_deref(), Some("bodies[0].com[1]"));
    }
}
