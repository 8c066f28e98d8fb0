//! The documentation's links: README.md and every markdown file under docs/ (the user
//! guide, MODEL.md, the benchmarks, the readings of the paper) point only at files that
//! exist and, through `#anchor`, at headings that exist in them, as GitHub resolves them.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// README.md and every `*.md` under docs/, recursively, sorted.
fn markdown_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("read docs/") {
            let path = entry.expect("read docs/ entry").path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|x| x == "md") {
                out.push(path);
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    walk(&root.join("docs"), &mut files);
    files.sort();
    files
}

/// `text` with its fenced code blocks (opened by three or more backticks or tildes; the
/// fence lines included) blanked; every newline is kept, so offsets still give line numbers.
fn strip_fences(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    // The open fence: its character and length.
    let mut fence: Option<(char, usize)> = None;
    for line in text.split_inclusive('\n') {
        let body = line.trim_start();
        let run = |c: char| body.chars().take_while(|&x| x == c).count();
        let blank = match fence {
            None => {
                for c in ['`', '~'] {
                    if run(c) >= 3 {
                        fence = Some((c, run(c)));
                    }
                }
                fence.is_some()
            }
            Some((c, n)) => {
                if run(c) >= n && body.trim_start_matches(c).trim().is_empty() {
                    fence = None;
                }
                true
            }
        };
        if blank {
            out.extend(line.chars().map(|c| if c == '\n' { '\n' } else { ' ' }));
        } else {
            out.push_str(line);
        }
    }
    out
}

/// Whether the line after the newline at `chars[newline]` is blank (a paragraph's end).
fn blank_line_after(chars: &[char], newline: usize) -> bool {
    chars[newline + 1..]
        .iter()
        .take_while(|&&c| c != '\n')
        .all(|c| c.is_whitespace())
}

/// `text` with its inline code spans blanked (a run of n backticks up to the next run of
/// exactly n, within one paragraph: spans may cross a line break, not a blank line);
/// newlines are kept.
fn strip_inline_code(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = chars.clone();
    let run_at = |i: usize| chars[i..].iter().take_while(|&&c| c == '`').count();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            i += 1;
            continue;
        }
        let n = run_at(i);
        let mut j = i + n;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '\n' && blank_line_after(&chars, j) {
                break; // a blank line ends the paragraph: no closing run
            }
            if chars[j] == '`' {
                let m = run_at(j);
                if m == n {
                    close = Some(j + m);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match close {
            Some(end) => {
                for c in &mut out[i..end] {
                    if *c != '\n' {
                        *c = ' ';
                    }
                }
                i = end;
            }
            None => i += n,
        }
    }
    out.into_iter().collect()
}

/// A link of a markdown file: the 1-based line of its target and the target as written.
#[derive(Debug, PartialEq)]
struct Link {
    line: usize,
    target: String,
}

/// Every link and image target of `text` outside code: inline `[text](target)` and
/// `![alt](target)` (an optional title after the target is dropped, `<target>` unwrapped)
/// and reference definitions `[label]: target`.
fn links(text: &str) -> Vec<Link> {
    let clean = strip_inline_code(&strip_fences(text));
    let chars: Vec<char> = clean.chars().collect();
    let line_at = |i: usize| 1 + chars[..i].iter().filter(|&&c| c == '\n').count();
    let mut found = Vec::new();
    for i in 1..chars.len() {
        if !(chars[i] == '(' && chars[i - 1] == ']') || (i >= 2 && chars[i - 2] == '\\') {
            continue;
        }
        // The `[` that opens the link text, within the paragraph.
        let mut depth = 0usize;
        let mut opened = false;
        for k in (0..i - 1).rev() {
            match chars[k] {
                ']' if k == 0 || chars[k - 1] != '\\' => depth += 1,
                '[' if k == 0 || chars[k - 1] != '\\' => {
                    if depth == 0 {
                        opened = true;
                        break;
                    }
                    depth -= 1;
                }
                '\n' if blank_line_after(&chars, k) => break,
                _ => {}
            }
        }
        if !opened {
            continue;
        }
        let mut j = i + 1;
        while j < chars.len() && (chars[j] == ' ' || chars[j] == '\n') {
            j += 1;
        }
        let start = j;
        let target: String = if chars.get(j) == Some(&'<') {
            chars[j + 1..]
                .iter()
                .take_while(|&&c| c != '>' && c != '\n')
                .collect()
        } else {
            let mut parens = 0usize;
            let mut t = String::new();
            for &c in &chars[j..] {
                match c {
                    '(' => parens += 1,
                    ')' if parens == 0 => break,
                    ')' => parens -= 1,
                    c if c.is_whitespace() => break,
                    _ => {}
                }
                t.push(c);
            }
            t
        };
        if !target.is_empty() {
            found.push(Link {
                line: line_at(start),
                target,
            });
        }
    }
    // Reference definitions: `[label]: target` at the start of a line (not footnotes).
    for (n, line) in clean.lines().enumerate() {
        let body = line.trim_start();
        if line.len() - body.len() > 3 || !body.starts_with('[') || body.starts_with("[^") {
            continue;
        }
        if let Some(end) = body.find("]:") {
            if let Some(target) = body[end + 2..].split_whitespace().next() {
                let target = target.trim_start_matches('<').trim_end_matches('>');
                found.push(Link {
                    line: n + 1,
                    target: target.to_string(),
                });
            }
        }
    }
    found.sort_by_key(|l| l.line);
    found
}

/// GitHub's anchor for a heading: lowercase, spaces to `-`, every character other than a
/// letter, a digit, `-` or `_` dropped (letters beyond ASCII, such as µ, kept). Links and
/// images in the heading count by their text.
fn slug(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading;
    // [text](url) → text, ![alt](url) → alt.
    while let Some(open) = rest.find('[') {
        let Some(mid) = rest[open..].find("](").map(|m| open + m) else {
            break;
        };
        let Some(close) = rest[mid..].find(')').map(|c| mid + c) else {
            break;
        };
        text.push_str(rest[..open].trim_end_matches('!'));
        text.push_str(&rest[open + 1..mid]);
        rest = &rest[close + 1..];
    }
    text.push_str(rest);
    text.trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors a markdown file offers: the slugs of its ATX (`## Title`) and setext
/// headings outside code blocks, repeated slugs numbered `-1`, `-2`… as GitHub does, and
/// the ids and names of `<a id="…">` / `<a name="…">` tags.
fn anchors(text: &str) -> HashSet<String> {
    let clean = strip_fences(text);
    let mut headings = Vec::new();
    let mut previous = "";
    for line in clean.lines() {
        let body = line.trim_start();
        let hashes = body.chars().take_while(|&c| c == '#').count();
        let indent = line.len() - body.len();
        if indent <= 3 && (1..=6).contains(&hashes) {
            let after = &body[hashes..];
            if after.is_empty() || after.starts_with(' ') || after.starts_with('\t') {
                // A closing run of `#` preceded by a space is not part of the title.
                let title = after.trim();
                let title = match title.trim_end_matches('#') {
                    t if t.ends_with(' ') || t.is_empty() => t.trim_end(),
                    _ => title,
                };
                headings.push(title.to_string());
            }
        } else if indent <= 3
            && !body.is_empty()
            && (body.trim_end().chars().all(|c| c == '=')
                || body.trim_end().chars().all(|c| c == '-'))
        {
            let p = previous.trim();
            if !p.is_empty() && !p.starts_with(['#', '|', '>', '-', '*', '+']) {
                headings.push(p.to_string());
            }
        }
        previous = line;
    }
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = HashSet::new();
    for h in headings {
        let s = slug(&h);
        let n = seen.entry(s.clone()).or_insert(0);
        out.insert(if *n == 0 { s } else { format!("{s}-{n}") });
        *n += 1;
    }
    for tag in clean.split("<a ").skip(1) {
        let tag = tag.split('>').next().unwrap_or("");
        for key in ["id=\"", "name=\""] {
            if let Some(at) = tag.find(key) {
                let value = &tag[at + key.len()..];
                out.insert(value.split('"').next().unwrap_or("").to_string());
            }
        }
    }
    out
}

/// `%XX` escapes decoded (as in `a%20b` or `#%C2%B5m`); anything else kept.
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(b)) => {
                out.push(b);
                i += 3;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Whether a link target leaves the repository (checked by no one here).
fn is_external(target: &str) -> bool {
    ["http://", "https://", "mailto:"]
        .iter()
        .any(|p| target.to_ascii_lowercase().starts_with(p))
}

/// Every relative link and image of README.md and docs/**/*.md resolves: the file or
/// folder it names exists relative to the markdown file's own folder, and a `#anchor`
/// (alone: into the same file) is the GitHub slug of a heading of the markdown file it
/// points into. Links inside fenced code blocks and inline code are not links. Every
/// broken link is listed, `file:line: target`, in one message.
#[test]
fn every_relative_link_in_the_docs_resolves() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = markdown_files();
    assert!(files.len() >= 4, "README.md and docs/*.md: found {files:?}");
    let mut anchor_cache: HashMap<PathBuf, HashSet<String>> = HashMap::new();
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).expect("read a markdown file");
        let dir = file.parent().expect("a file's folder");
        let shown = file
            .strip_prefix(root)
            .unwrap_or(file)
            .display()
            .to_string();
        for link in links(&text) {
            if is_external(&link.target) {
                continue;
            }
            checked += 1;
            let (path, anchor) = match link.target.split_once('#') {
                Some((p, a)) => (percent_decode(p), Some(percent_decode(a))),
                None => (percent_decode(&link.target), None),
            };
            let target = if path.is_empty() {
                file.clone()
            } else {
                dir.join(&path)
            };
            let mut report = |why: &str| {
                broken.push(format!("{shown}:{}: {} ({why})", link.line, link.target));
            };
            if !target.exists() {
                report("no such file");
                continue;
            }
            let Some(anchor) = anchor else { continue };
            if target.extension().is_none_or(|x| x != "md") {
                report("an anchor into a file that is not markdown");
                continue;
            }
            let known = anchor_cache.entry(target.clone()).or_insert_with(|| {
                anchors(&std::fs::read_to_string(&target).expect("read a linked markdown file"))
            });
            if !known.contains(&anchor) {
                report("no heading with this anchor");
            }
        }
    }
    // The parser finding nothing would pass vacuously: README.md alone has dozens.
    assert!(
        checked >= 20,
        "only {checked} relative links found in {} files",
        files.len()
    );
    assert!(
        broken.is_empty(),
        "{} broken link(s) in README.md and docs/:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

/// The slug is GitHub's: lowercase, spaces to `-`, punctuation dropped, `-`, `_`, digits
/// and non-ASCII letters kept, links and inline code by their text.
#[test]
fn a_heading_slug_is_githubs() {
    assert_eq!(
        slug("Beyond the paper: the 3-D quarter cell"),
        "beyond-the-paper-the-3-d-quarter-cell"
    );
    assert_eq!(
        slug("What the sweeps answer: when does the nucleus penetrate?"),
        "what-the-sweeps-answer-when-does-the-nucleus-penetrate"
    );
    assert_eq!(
        slug("Phases the cell starts itself: beyond the paper's clock"),
        "phases-the-cell-starts-itself-beyond-the-papers-clock"
    );
    assert_eq!(slug("Mean ‖E‖ at 5 µm, T_g0"), "mean-e-at-5-µm-t_g0");
    assert_eq!(slug("`cellsim sweep` runs"), "cellsim-sweep-runs");
    assert_eq!(
        slug("See [the guide](guide/README.md) now"),
        "see-the-guide-now"
    );
    assert_eq!(slug("Speed and accuracy  "), "speed-and-accuracy");
}

/// Links are found in text, images and reference definitions with their lines, and not
/// in fenced code blocks or inline code (also a code span across a line break); a
/// parenthesis after a word is not a link.
#[test]
fn links_are_found_outside_code_only() {
    let text = "\
# Title

A [link](a.md#x) and an ![image](../p.png \"title\"), f(x) and [x] (y).
```sh
cellsim [not](code.md)
```
Inline `[no](c.md)` and a span `across
[no](d.md)` lines, then [`code text`](<e f.md>).

[ref]: g.md
";
    let found = links(text);
    let targets: Vec<(usize, &str)> = found.iter().map(|l| (l.line, l.target.as_str())).collect();
    assert_eq!(
        targets,
        [(3, "a.md#x"), (3, "../p.png"), (8, "e f.md"), (10, "g.md")]
    );
}

/// A file's anchors: its headings' slugs, repeats numbered as GitHub does, setext headings
/// and `<a id>` tags, and no `#` line of a code block.
#[test]
fn anchors_are_the_headings_outside_code() {
    let text = "\
# Guide
## Results ##
## Results
```sh
# not a heading
```
Setext title
------------
<a id=\"here\"></a>
";
    let found = anchors(text);
    let expected: HashSet<String> = ["guide", "results", "results-1", "setext-title", "here"]
        .iter()
        .map(ToString::to_string)
        .collect();
    assert_eq!(found, expected);
    assert_eq!(percent_decode("%C2%B5m%20x"), "µm x");
}
