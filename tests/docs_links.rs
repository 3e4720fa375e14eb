//! The documentation as a test (issue 42): every relative link and image of README.md, of every
//! Markdown file under docs/ and examples/, and of meshes/README.md points at a file or directory
//! that exists, and every `#anchor` into a Markdown file (or within one) names one of its
//! headings by GitHub's rule; README.md is a page for a user, at most 300 lines, with its two
//! commands (the main job, then the tests) in code blocks within its first 25 lines.
//!
//! Links inside code (fenced blocks and inline spans) are not links and are not checked; links
//! to http(s) and mailto are not followed.

use std::collections::HashMap;
use std::fs;
use std::path::{Component, Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files whose links are checked: README.md, docs/**, examples/** and
/// meshes/README.md.
fn markdown_files() -> Vec<PathBuf> {
    let root = root();
    let mut files = vec![root.join("README.md")];
    for dir in ["docs", "examples"] {
        collect_markdown(&root.join(dir), &mut files);
    }
    let meshes = root.join("meshes/README.md");
    if meshes.is_file() {
        files.push(meshes);
    }
    files.sort();
    files
}

fn collect_markdown(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect_markdown(&path, out);
        } else if path.extension().is_some_and(|e| e == "md") {
            out.push(path);
        }
    }
}

/// Whether each line lies in a fenced code block (its fences included).
fn code_lines(text: &str) -> Vec<bool> {
    let mut fence: Option<(char, usize)> = None;
    let mut out = Vec::new();
    for line in text.lines() {
        let indent = line.len() - line.trim_start_matches(' ').len();
        let t = line.trim_start_matches(' ');
        let run = |c: char| t.chars().take_while(|&x| x == c).count();
        let opener = if indent <= 3 {
            ['`', '~'].into_iter().map(|c| (c, run(c))).find(|&(_, n)| n >= 3)
        } else {
            None
        };
        match (fence, opener) {
            (None, Some(f)) => {
                fence = Some(f);
                out.push(true);
            }
            (Some((c, n)), Some((c2, n2))) if c == c2 && n2 >= n && t[n2..].trim().is_empty() => {
                fence = None;
                out.push(true);
            }
            (f, _) => out.push(f.is_some()),
        }
    }
    out
}

/// The line without its inline code spans (a run of n backticks up to the next run of exactly
/// n); an unclosed run is kept as text.
fn without_code_spans(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let n = chars[i..].iter().take_while(|&&c| c == '`').count();
        let mut j = i + n;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '`' {
                let m = chars[j..].iter().take_while(|&&c| c == '`').count();
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
                out.push(' ');
                i = end;
            }
            None => {
                out.extend(&chars[i..i + n]);
                i += n;
            }
        }
    }
    out
}

/// The targets of the inline links and images on a line (code spans already removed):
/// what stands in the parentheses after `](`, without a title.
fn link_targets(line: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        let after_trim = after.trim_start();
        let target = if let Some(inner) = after_trim.strip_prefix('<') {
            inner.split('>').next().unwrap_or("").to_string()
        } else {
            let mut depth = 0usize;
            let mut end = after_trim.len();
            for (k, c) in after_trim.char_indices() {
                match c {
                    '(' => depth += 1,
                    ')' if depth == 0 => {
                        end = k;
                        break;
                    }
                    ')' => depth -= 1,
                    c if c.is_whitespace() => {
                        end = k;
                        break;
                    }
                    _ => {}
                }
            }
            after_trim[..end].to_string()
        };
        targets.push(target);
        rest = after;
    }
    // reference definitions: `[label]: target`
    let t = line.trim_start();
    if line.len() - t.len() <= 3 && t.starts_with('[') {
        if let Some(close) = t.find("]:") {
            if let Some(target) = t[close + 2..].split_whitespace().next() {
                targets.push(target.trim_matches(|c| c == '<' || c == '>').to_string());
            }
        }
    }
    targets
}

/// GitHub's anchor of a heading's text: lower case, spaces to '-', every character but letters,
/// digits, '-' and '_' dropped (so `§`, `–`, `.`, `'` and `:` vanish).
fn slug(heading: &str) -> String {
    let text = rendered(heading);
    let mut out = String::new();
    for c in text.trim().chars() {
        if c == ' ' {
            out.push('-');
        } else if c.is_alphanumeric() || c == '-' || c == '_' {
            out.extend(c.to_lowercase());
        }
    }
    out
}

/// A heading's text as rendered: code spans keep their text, links and images their text.
fn rendered(heading: &str) -> String {
    let mut s = heading.replace('`', "");
    // [text](target) -> text
    while let Some(at) = s.find("](") {
        let Some(open) = s[..at].rfind('[') else { break };
        let Some(close) = s[at..].find(')') else { break };
        let text = s[open + 1..at].to_string();
        let bang = open > 0 && s.as_bytes()[open - 1] == b'!';
        let start = if bang { open - 1 } else { open };
        s.replace_range(start..at + close + 1, &text);
    }
    s
}

/// The anchors of a Markdown text's ATX headings, duplicates numbered as GitHub does (`x`,
/// `x-1`, `x-2`, …).
fn anchors(text: &str) -> Vec<String> {
    let code = code_lines(text);
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    for (line, in_code) in text.lines().zip(code) {
        if in_code {
            continue;
        }
        let t = line.trim_start_matches(' ');
        if line.len() - t.len() > 3 {
            continue;
        }
        let hashes = t.chars().take_while(|&c| c == '#').count();
        if !(1..=6).contains(&hashes) {
            continue;
        }
        let rest = &t[hashes..];
        if !(rest.is_empty() || rest.starts_with(' ') || rest.starts_with('\t')) {
            continue;
        }
        let mut title = rest.trim();
        // a closing sequence of #s
        let stripped = title.trim_end_matches('#');
        if stripped.len() < title.len() && (stripped.is_empty() || stripped.ends_with(' ')) {
            title = stripped.trim_end();
        }
        let base = slug(title);
        let n = seen.entry(base.clone()).or_insert(0);
        out.push(if *n == 0 { base.clone() } else { format!("{base}-{n}") });
        *n += 1;
    }
    out
}

fn percent_decoded(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(b) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(b);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// `a/b/../c` without touching the file system.
fn normalised(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

fn display(path: &Path) -> String {
    path.strip_prefix(root()).unwrap_or(path).display().to_string()
}

/// Every broken link of one Markdown file, as `file:line: what`.
fn broken_links(file: &Path, text: &str) -> Vec<String> {
    let root = root();
    let dir = file.parent().unwrap_or(&root).to_path_buf();
    let code = code_lines(text);
    let mut anchor_cache: HashMap<PathBuf, Vec<String>> = HashMap::new();
    let mut failures = Vec::new();
    for (i, (line, in_code)) in text.lines().zip(code).enumerate() {
        if in_code {
            continue;
        }
        for target in link_targets(&without_code_spans(line)) {
            let lower = target.to_ascii_lowercase();
            if target.is_empty()
                || lower.starts_with("http://")
                || lower.starts_with("https://")
                || lower.starts_with("mailto:")
                || lower.contains("://")
            {
                if target.is_empty() {
                    failures.push(format!("{}:{}: an empty link target", display(file), i + 1));
                }
                continue;
            }
            let (path_part, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let path_part = percent_decoded(path_part);
            let resolved = if path_part.is_empty() {
                file.to_path_buf()
            } else if let Some(abs) = path_part.strip_prefix('/') {
                normalised(&root.join(abs))
            } else {
                normalised(&dir.join(path_part.as_str()))
            };
            if !resolved.exists() {
                failures.push(format!(
                    "{}:{}: `{target}`: {} does not exist",
                    display(file),
                    i + 1,
                    display(&resolved)
                ));
                continue;
            }
            let Some(anchor) = anchor else { continue };
            if !(resolved.is_file() && resolved.extension().is_some_and(|e| e == "md")) {
                continue;
            }
            let known = anchor_cache.entry(resolved.clone()).or_insert_with(|| {
                let text = if resolved == file {
                    text.to_string()
                } else {
                    fs::read_to_string(&resolved).unwrap()
                };
                anchors(&text)
            });
            let anchor = percent_decoded(anchor);
            if !known.contains(&anchor) {
                let near: Vec<&String> = known
                    .iter()
                    .filter(|a| {
                        let key = anchor.split('-').find(|w| w.len() > 3).unwrap_or(&anchor);
                        a.contains(key)
                    })
                    .take(3)
                    .collect();
                failures.push(format!(
                    "{}:{}: `{target}`: {} has no heading with the anchor #{anchor}{}",
                    display(file),
                    i + 1,
                    display(&resolved),
                    if near.is_empty() {
                        String::new()
                    } else {
                        format!(" (near: {near:?})")
                    }
                ));
            }
        }
    }
    failures
}

#[test]
fn every_relative_link_of_the_documentation_exists() {
    let files = markdown_files();
    assert!(files.len() >= 5, "only {} Markdown files found", files.len());
    let mut failures = Vec::new();
    let mut checked = 0;
    for file in &files {
        let text = fs::read_to_string(file).unwrap();
        checked += code_lines(&text)
            .iter()
            .zip(text.lines())
            .filter(|(c, _)| !**c)
            .map(|(_, l)| link_targets(&without_code_spans(l)).len())
            .sum::<usize>();
        failures.extend(broken_links(file, &text));
    }
    assert!(checked >= 50, "only {checked} links found in {} files", files.len());
    assert!(
        failures.is_empty(),
        "{} broken link(s) in the documentation:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The issue's acceptance for README.md: at most ~300 lines, and the two commands, the main job
/// on the shipped default and then the tests, in code blocks within its first 25 lines (they are
/// what .ci/run calls).
#[test]
fn the_readme_is_short_with_its_two_commands_first() {
    let text = fs::read_to_string(root().join("README.md")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len() <= 300, "README.md has {} lines, more than 300", lines.len());
    let code = code_lines(&text);
    let find = |command: &str| {
        lines
            .iter()
            .zip(&code)
            .position(|(l, c)| *c && l.trim() == command)
            .unwrap_or_else(|| panic!("README.md has no code line `{command}`"))
    };
    let main_job = find("cargo run --release -- solve meshes/rect_q1_h32.msh --out runs/paper");
    let tests = find("cargo test --release");
    assert!(
        main_job < 25,
        "the main command is on line {}, not within the first 25",
        main_job + 1
    );
    assert!(
        tests < 25,
        "the test command is on line {}, not within the first 25",
        tests + 1
    );
    assert!(
        main_job < tests,
        "the main command (line {}) comes after the tests (line {})",
        main_job + 1,
        tests + 1
    );
}

/// The checker itself: GitHub's anchors of headings like method.md's, and a missing file, a
/// missing anchor in another file and in the same file are all reported, with their lines.
#[test]
fn the_checker_finds_broken_links() {
    assert_eq!(slug("§9 The linear-algebra seams"), "9-the-linear-algebra-seams");
    assert_eq!(slug("9.2 Many contact nodes"), "92-many-contact-nodes");
    assert_eq!(
        slug("Friction: Cattaneo–Mindlin partial slip"),
        "friction-cattaneomindlin-partial-slip"
    );
    assert_eq!(
        slug("The paper's Tables 1–2, reproduced"),
        "the-papers-tables-12-reproduced"
    );
    assert_eq!(slug("12.4 Obstacles in `hvi plot`"), "124-obstacles-in-hvi-plot");
    assert_eq!(
        slug("method.md §9.2 — many contact nodes"),
        "methodmd-92--many-contact-nodes"
    );
    assert_eq!(anchors("# A\n\n```sh\n# not a heading\n```\n## A\n"), ["a", "a-1"]);
    let readme = root().join("README.md");
    let text = "# Title\n\
                [fine](docs/method.md#92-many-contact-nodes) and ![fine](examples/figures/paper_h32_deformed.png)\n\
                [missing file](docs/no-such-page.md)\n\
                `[in code](docs/no-such-page.md)`\n\
                [missing anchor](docs/method.md#no-such-heading) [here](#title) [not here](#nowhere)\n\
                ```text\n[in a block](nowhere.md)\n```\n\
                [outside](https://example.org/x.md)\n";
    let failures = broken_links(&readme, text);
    assert_eq!(failures.len(), 3, "{failures:#?}");
    assert!(
        failures[0].starts_with("README.md:3: `docs/no-such-page.md`"),
        "{}",
        failures[0]
    );
    assert!(
        failures[1].starts_with("README.md:5: `docs/method.md#no-such-heading`"),
        "{}",
        failures[1]
    );
    assert!(failures[2].starts_with("README.md:5: `#nowhere`"), "{}", failures[2]);
}
