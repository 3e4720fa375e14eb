//! The layering of `src/` as a test (docs/README.md "Layers"): data flows one way, from the
//! expressions and the mesh up to the application, and this test keeps it so.
//!
//! Every file under `src/` belongs to the layer of its top-level module in [`LAYERS`]. The test
//! reads each file, drops comments and string literals, and follows every path that starts with
//! `crate::`, `super::` or `self::` (in `use` trees and in code) to the file that defines it,
//! seeing through `pub use` re-exports of a module's `mod.rs`. It fails, naming file and line:
//! * on an import from a lower layer into a higher one;
//! * on any cycle between files (two files that import each other, directly or around a ring),
//!   within a layer or a module as much as across them.
//!
//! There is no list of exceptions, and there is to be none.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first. A module may import from its own layer's other modules (as long as
/// no cycle forms) and from any layer below; never from above.
const LAYERS: &[&[&str]] = &[
    // expressions of position, time and state: parsed once, evaluated everywhere; the global
    // allocator's clean end on an allocation failure; the time levels of a run and automatic steps
    &["expr", "alloc", "time"],
    // the geometry: reference cells, their maps and quadrature, meshes and their readers
    &["mesh"],
    // sparse and dense linear algebra: storage, ordering, the Cholesky factor
    &["linalg"],
    // constitutive laws: elasticity tensors, relaxation kernels
    &["material"],
    // finite elements on a mesh: patterns, assembly, loads, stresses
    &["fem"],
    // the memory term and the contact laws with their solver
    &["history", "contact"],
    // the scene a user writes
    &["scene"],
    // the method: one simulation, its backends, the time loop
    &["solver"],
    // files written and read back
    &["output"],
    // pictures
    &["plot"],
    // convergence studies
    &["study"],
    // the application behind the commands: solve, check, the sinks and the summary
    &["app"],
    // the PETSc driver, which reuses the application's sinks, summary and reports
    &["petsc"],
    &["lib", "main"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&module))
}

/// A source file as a module path: `src/fem/pattern.rs` is `["fem", "pattern"]`,
/// `src/fem/mod.rs` is `["fem"]`, `src/lib.rs` is `["lib"]`.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap();
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs").to_string();
    if stem != "mod" {
        parts.push(stem);
    }
    parts
}

/// The source with comments, string and character literals blanked out (newlines kept, so
/// that offsets still give line numbers).
fn strip(source: &str) -> String {
    let b = source.as_bytes();
    let mut out = b.to_vec();
    let mut i = 0;
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                let end = source[i..].find('\n').map_or(b.len(), |n| i + n);
                blank(&mut out, i, end);
                i = end;
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let (mut depth, mut j) = (1, i + 2);
                while j < b.len() && depth > 0 {
                    if b[j] == b'/' && b.get(j + 1) == Some(&b'*') {
                        depth += 1;
                        j += 2;
                    } else if b[j] == b'*' && b.get(j + 1) == Some(&b'/') {
                        depth -= 1;
                        j += 2;
                    } else {
                        j += 1;
                    }
                }
                blank(&mut out, i, j);
                i = j;
            }
            b'r' if !ident_char(b, i.wrapping_sub(1)) && matches!(b.get(i + 1), Some(b'"') | Some(b'#')) => {
                // a raw string r"…", r#"…"#
                let mut j = i + 1;
                let mut hashes = 0;
                while b.get(j) == Some(&b'#') {
                    hashes += 1;
                    j += 1;
                }
                if b.get(j) != Some(&b'"') {
                    i += 1;
                    continue;
                }
                let close: String = std::iter::once('"').chain((0..hashes).map(|_| '#')).collect();
                let end = source[j + 1..]
                    .find(&close)
                    .map_or(b.len(), |n| j + 1 + n + close.len());
                blank(&mut out, i, end);
                i = end;
            }
            b'"' => {
                let mut j = i + 1;
                while j < b.len() && b[j] != b'"' {
                    j += if b[j] == b'\\' { 2 } else { 1 };
                }
                blank(&mut out, i, (j + 1).min(b.len()));
                i = j + 1;
            }
            b'\'' => {
                // a character literal ('x', '\n', '\u{..}') or a lifetime ('a)
                if b.get(i + 1) == Some(&b'\\') {
                    let end = source[i + 2..].find('\'').map_or(b.len(), |n| i + 2 + n + 1);
                    blank(&mut out, i, end);
                    i = end;
                } else {
                    let ch_len = source[i + 1..].chars().next().map_or(1, char::len_utf8);
                    if b.get(i + 1 + ch_len) == Some(&b'\'') {
                        blank(&mut out, i, i + 2 + ch_len);
                        i += 2 + ch_len;
                    } else {
                        i += 1;
                    }
                }
            }
            _ => i += 1,
        }
    }
    String::from_utf8(out).unwrap()
}

fn ident_char(b: &[u8], i: usize) -> bool {
    b.get(i).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
}

/// Expands a use tree (`crate::a::{b, c::{d, e}}`) into its paths.
fn expand_use_tree(tree: &str) -> Vec<Vec<String>> {
    fn parse(s: &str, prefix: &[String], out: &mut Vec<Vec<String>>) {
        // split s at top-level commas
        let mut depth = 0;
        let mut start = 0;
        let mut items = Vec::new();
        for (i, c) in s.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    items.push(&s[start..i]);
                    start = i + 1;
                }
                _ => {}
            }
        }
        items.push(&s[start..]);
        for item in items {
            let item = item.trim();
            if item.is_empty() {
                continue;
            }
            if let Some(open) = item.find('{') {
                let head = item[..open].trim().trim_end_matches("::");
                let inner = &item[open + 1..item.rfind('}').unwrap_or(item.len())];
                let mut p = prefix.to_vec();
                p.extend(segments(head));
                parse(inner, &p, out);
            } else {
                let path = item.split(" as ").next().unwrap().trim();
                let mut p = prefix.to_vec();
                p.extend(segments(path));
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    parse(tree, &[], &mut out);
    out
}

fn segments(path: &str) -> Vec<String> {
    path.split("::")
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

/// One import found in a file: the path as written, absolute in the crate, and its line.
struct Import {
    line: usize,
    path: Vec<String>,
}

/// The crate-relative paths a file refers to, from `use` statements and from paths in code.
fn imports(module: &[String], code: &str) -> Vec<Import> {
    let line_of = |offset: usize| code[..offset].matches('\n').count() + 1;
    // the file's child modules (`mod name;`): a path `name::…` in it reaches into that child
    let children: Vec<String> = code
        .split(';')
        .filter_map(|statement| {
            let words: Vec<&str> = statement.split_whitespace().collect();
            let at = words.iter().rposition(|w| *w == "mod")?;
            (at + 2 == words.len()).then(|| words[at + 1].to_string())
        })
        .filter(|name| name.chars().all(|c| c.is_alphanumeric() || c == '_'))
        .collect();
    // `super` of a file `a/b.rs` (module a::b) is `a`; of `a/mod.rs` (module a) it is the crate
    let parent = |m: &[String]| m[..m.len().saturating_sub(1)].to_vec();
    let absolute = |p: &[String], module: &[String]| -> Option<Vec<String>> {
        let first = p.first()?;
        let mut base: Vec<String> = match first.as_str() {
            "crate" => Vec::new(),
            "self" => module.to_vec(),
            "super" => parent(module),
            child if children.iter().any(|c| c == child) => {
                let mut m = module.to_vec();
                m.push(child.to_string());
                return Some(m.into_iter().chain(p[1..].iter().cloned()).collect());
            }
            _ => return None,
        };
        let mut rest = &p[1..];
        while rest.first().is_some_and(|s| s == "super") {
            base = parent(&base);
            rest = &rest[1..];
        }
        base.extend(rest.iter().cloned());
        Some(base)
    };
    // inline modules (`mod tests { … }`): `super` inside one is the file's own module
    let bytes = code.as_bytes();
    let mut inline = Vec::new();
    let mut i = 0;
    while let Some(n) = code[i..].find("mod ") {
        let at = i + n;
        i = at + 4;
        if ident_char(bytes, at.wrapping_sub(1)) {
            continue;
        }
        let rest = &code[at + 4..];
        let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let after = rest[name.len()..].trim_start();
        if name.is_empty() || !after.starts_with('{') {
            continue;
        }
        let open = at + 4 + rest.find('{').unwrap();
        let (mut depth, mut j) = (0, open);
        while j < bytes.len() {
            match bytes[j] {
                b'{' => depth += 1,
                b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                _ => {}
            }
            j += 1;
        }
        inline.push((open, j, name));
    }
    let module_at = |offset: usize| -> Vec<String> {
        let mut m = module.to_vec();
        for (s, e, name) in &inline {
            if offset > *s && offset < *e {
                m.push(name.clone());
            }
        }
        m
    };
    let absolute = |p: &[String], at: usize| absolute(p, &module_at(at));
    let mut found = Vec::new();
    // `use` statements, whose trees may span lines
    let mut i = 0;
    let mut use_spans = Vec::new();
    while let Some(n) = code[i..].find("use ") {
        let at = i + n;
        i = at + 4;
        if ident_char(bytes, at.wrapping_sub(1)) {
            continue;
        }
        let Some(end) = code[at..].find(';').map(|e| at + e) else {
            break;
        };
        use_spans.push((at, end));
        let tree: String = code[at + 4..end].split_whitespace().collect::<Vec<_>>().join(" ");
        for path in expand_use_tree(&tree) {
            if let Some(abs) = absolute(&path, at) {
                found.push(Import {
                    line: line_of(at),
                    path: abs,
                });
            }
        }
        i = end;
    }
    // paths in code: crate::a::b, super::a, self::a
    let roots = ["crate", "super", "self"]
        .into_iter()
        .chain(children.iter().map(String::as_str));
    for root in roots {
        let pattern = format!("{root}::");
        let mut i = 0;
        while let Some(n) = code[i..].find(&pattern) {
            let at = i + n;
            i = at + pattern.len();
            if ident_char(bytes, at.wrapping_sub(1))
                || (at >= 2 && &code[at - 2..at] == "::")
                || use_spans.iter().any(|&(s, e)| at >= s && at < e)
            {
                continue;
            }
            let mut end = at;
            while end < bytes.len()
                && (ident_char(bytes, end) || (bytes[end] == b':' && bytes.get(end + 1) == Some(&b':')))
            {
                end += if bytes[end] == b':' { 2 } else { 1 };
            }
            let path = segments(&code[at..end]);
            if let Some(abs) = absolute(&path, at) {
                found.push(Import {
                    line: line_of(at),
                    path: abs,
                });
            }
        }
    }
    found
}

struct Source {
    file: PathBuf,
    module: Vec<String>,
    code: String,
}

fn sources() -> (PathBuf, Vec<Source>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    let sources = files
        .into_iter()
        .map(|file| {
            let text = std::fs::read_to_string(&file).unwrap();
            Source {
                module: module_path(&src, &file),
                code: strip(&text),
                file,
            }
        })
        .collect();
    (src, sources)
}

/// Maps a crate-relative path to the file that defines its item: the longest prefix that is a
/// module file, seeing through `pub use child::Name` re-exports of that module.
fn resolve(
    path: &[String],
    modules: &BTreeMap<Vec<String>, usize>,
    reexports: &BTreeMap<(usize, String), Vec<String>>,
    sources: &[Source],
) -> Option<usize> {
    let mut depth = 0;
    for k in (1..=path.len()).rev() {
        if modules.contains_key(&path[..k]) {
            depth = k;
            break;
        }
    }
    if depth == 0 {
        // crate root items (lib.rs)
        return modules.get(&vec!["lib".to_string()]).copied();
    }
    let mut file = modules[&path[..depth]];
    let mut guard = 0;
    while let Some(name) = path.get(depth) {
        // an explicit re-export, else a glob re-export (`pub use child::*`) of a module that
        // defines the name
        let glob = || {
            reexports
                .range((file, "*".to_string())..)
                .take_while(|((f, n), _)| *f == file && n.starts_with('*'))
                .find_map(|(_, target)| {
                    let defines = modules.get(target).is_some_and(|&t| defines(&sources[t].code, name));
                    defines.then_some(target)
                })
        };
        let Some(target) = reexports.get(&(file, name.clone())).or_else(glob) else {
            break;
        };
        let Some(&next) = modules.get(target) else {
            break;
        };
        if next == file || guard > 8 {
            break;
        }
        file = next;
        guard += 1;
    }
    Some(file)
}

#[test]
fn imports_run_down_the_layers_and_no_files_import_each_other() {
    let (src, sources) = sources();
    assert!(
        sources.len() > 50,
        "found only {} source files under {}",
        sources.len(),
        src.display()
    );
    let modules: BTreeMap<Vec<String>, usize> =
        sources.iter().enumerate().map(|(i, s)| (s.module.clone(), i)).collect();

    let mut problems = Vec::new();
    for s in &sources {
        if layer_of(&s.module[0]).is_none() {
            problems.push(format!(
                "{}: module `{}` has no layer in tests/layers.rs LAYERS",
                s.file.display(),
                s.module[0]
            ));
        }
    }

    // `pub use child::Name` (or `pub use self::child::Name`) in a module file re-exports
    let mut reexports = BTreeMap::new();
    for (i, s) in sources.iter().enumerate() {
        let is_mod = s.file.file_name().is_some_and(|f| f == "mod.rs" || f == "lib.rs");
        if !is_mod {
            continue;
        }
        let mut at = 0;
        while let Some(n) = s.code[at..].find("use ") {
            let start = at + n + 4;
            let Some(end) = s.code[start..].find(';').map(|e| start + e) else {
                break;
            };
            at = end;
            if !is_reexport(&s.code[..start - 4]) {
                continue;
            }
            let tree: String = s.code[start..end].split_whitespace().collect::<Vec<_>>().join(" ");
            for path in expand_use_tree(&tree) {
                let mut full = if path[0] == "self" {
                    let mut m = s.module.clone();
                    m.extend(path[1..].iter().cloned());
                    m
                } else if path[0] == "crate" {
                    path[1..].to_vec()
                } else {
                    let mut m = if s.module == ["lib"] {
                        Vec::new()
                    } else {
                        s.module.clone()
                    };
                    m.extend(path.iter().cloned());
                    m
                };
                let name = full.pop().unwrap();
                if name == "*" {
                    // globs keyed "*0", "*1", … so that a module may have several
                    let k = reexports
                        .range((i, "*".to_string())..)
                        .take_while(|((f, n), _)| *f == i && n.starts_with('*'))
                        .count();
                    reexports.insert((i, format!("*{k}")), full);
                } else {
                    reexports.insert((i, name), full);
                }
            }
        }
    }

    // the file graph and the layer check
    let mut edges: BTreeMap<usize, BTreeMap<usize, usize>> = BTreeMap::new();
    for (i, s) in sources.iter().enumerate() {
        let from_layer = layer_of(&s.module[0]);
        for import in imports(&s.module, &s.code) {
            if import.path.is_empty() {
                continue;
            }
            let Some(j) = resolve(&import.path, &modules, &reexports, &sources) else {
                continue;
            };
            if j == i {
                continue;
            }
            let to = &sources[j].module;
            // a module's mod.rs declaring and re-exporting its children is not an import
            let is_child = to.len() > s.module.len() && to[..s.module.len()] == s.module[..];
            let reexport_line = s.code.lines().nth(import.line - 1).unwrap_or("");
            if is_child && is_reexport(&reexport_line[..reexport_line.find("use ").unwrap_or(0)]) {
                continue;
            }
            if let (Some(a), Some(b)) = (from_layer, layer_of(&to[0])) {
                if b > a {
                    problems.push(format!(
                        "{}:{}: `{}` (layer {a}) imports `{}` (layer {b}), a higher layer",
                        rel(&src, &s.file),
                        import.line,
                        s.module[0],
                        import.path.join("::"),
                    ));
                }
            }
            edges.entry(i).or_default().entry(j).or_insert(import.line);
        }
    }

    // cycles between files (Tarjan's strongly connected components)
    for component in strongly_connected(sources.len(), &edges) {
        if component.len() < 2 {
            continue;
        }
        let set: BTreeSet<usize> = component.iter().copied().collect();
        let mut lines = Vec::new();
        for &a in &component {
            for (&b, &line) in edges.get(&a).into_iter().flatten() {
                if set.contains(&b) {
                    lines.push(format!(
                        "    {}:{line} imports {}",
                        rel(&src, &sources[a].file),
                        rel(&src, &sources[b].file)
                    ));
                }
            }
        }
        problems.push(format!("a cycle between files:\n{}", lines.join("\n")));
    }

    assert!(
        problems.is_empty(),
        "the layering of src/ is broken ({} problems):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// True if `code` defines an item called `name` at any depth (struct, enum, fn, …).
fn defines(code: &str, name: &str) -> bool {
    [
        "struct", "enum", "fn", "const", "static", "type", "trait", "mod", "union",
    ]
    .iter()
    .any(|kind| {
        let pattern = format!("{kind} {name}");
        code.match_indices(&pattern).any(|(at, _)| {
            let end = at + pattern.len();
            !ident_char(code.as_bytes(), end) && !ident_char(code.as_bytes(), at.wrapping_sub(1))
        })
    })
}

/// True if the text before a `use` ends in a visibility (`pub`, `pub(crate)`, `pub(super)`): a
/// re-export.
fn is_reexport(before: &str) -> bool {
    let before = before.trim_end();
    before.ends_with("pub")
        || (before.ends_with(')') && before.rfind("pub(").is_some_and(|p| !before[p..].contains('\n')))
}

fn rel(src: &Path, file: &Path) -> String {
    format!("src/{}", file.strip_prefix(src).unwrap().display())
}

fn strongly_connected(n: usize, edges: &BTreeMap<usize, BTreeMap<usize, usize>>) -> Vec<Vec<usize>> {
    struct State<'a> {
        edges: &'a BTreeMap<usize, BTreeMap<usize, usize>>,
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        let targets: Vec<usize> = s.edges.get(&v).map(|m| m.keys().copied().collect()).unwrap_or_default();
        for w in targets {
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            s.out.push(component);
        }
    }
    let mut s = State {
        edges,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The checker itself: a lower layer importing a higher one, a cycle, a commented-out import
/// and an import inside a string are told apart.
#[test]
fn the_checker_sees_use_trees_and_ignores_comments_and_strings() {
    let code = strip(
        "use crate::{mesh::Cell, fem::{pattern::Pattern, assembly}};\n\
         // use crate::app::x;\n\
         let s = \"crate::plot::y\"; let c = '\"'; fn f<'a>(x: &'a str) {}\n\
         let v = super::super::linalg::Factor::new();\n",
    );
    let module = vec!["solver".to_string(), "step".to_string()];
    let found: Vec<(usize, String)> = imports(&module, &code)
        .into_iter()
        .map(|i| (i.line, i.path.join("::")))
        .collect();
    assert_eq!(
        found,
        vec![
            (1, "mesh::Cell".to_string()),
            (1, "fem::pattern::Pattern".to_string()),
            (1, "fem::assembly".to_string()),
            (4, "linalg::Factor::new".to_string()),
        ]
    );
}

/// faer is the linear-algebra layer's: the rest of hvi sees its own types and slices
/// (`linalg::dense` for the contact solve's small dense matrices).
#[test]
fn faer_stays_in_linalg() {
    let (src, sources) = sources();
    let outside: Vec<String> = sources
        .iter()
        .filter(|s| s.module[0] != "linalg")
        .flat_map(|s| {
            s.code
                .match_indices("faer::")
                .filter(|(at, _)| !ident_char(s.code.as_bytes(), at.wrapping_sub(1)) && !s.code[..*at].ends_with("::"))
                .map(|(at, _)| format!("{}:{}", rel(&src, &s.file), s.code[..at].matches('\n').count() + 1))
        })
        .collect();
    assert!(
        outside.is_empty(),
        "faer used outside src/linalg/ at:\n{}",
        outside.join("\n")
    );
}
