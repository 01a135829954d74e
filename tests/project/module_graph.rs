//! No import circles in src/: every `crate::…`, `super::…` and `self::…` path of every file
//! (outside comments, strings, `#[cfg(test)]` modules and `tests.rs` files) is an edge from the file's module to
//! the file that defines the path's longest existing prefix (through `pub use` re-exports of a
//! module file). Two graphs must be acyclic: the top-level modules of the crate, and the files
//! (a file's paths into its own ancestors — `super::Thing` of mod.rs — are not edges). The
//! graphs are of the library (src/lib.rs's modules); the binary's modules (src/main.rs's: the
//! command line) are not in the library and reach it as `momentlab::…` only. The top-level
//! modules keep the order of the data flow ([`LAYERS`]): none imports a later one.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A module path from the crate root, e.g. `["search", "sweep"]`.
type Module = Vec<String>;
type Graph = BTreeMap<String, BTreeSet<String>>;

/// `src` with comments removed and string and character literals emptied (lifetimes kept).
fn lex(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    while i < b.len() {
        let c = b[i];
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if b[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if (c == b'r' || c == b'b') && (i == 0 || !ident(b[i - 1])) && raw_start(&b[i..]) {
            // r"…", r#"…"#, br"…"
            let mut j = i + if c == b'b' { 2 } else { 1 };
            let mut hashes = 0;
            while b[j] == b'#' {
                hashes += 1;
                j += 1;
            }
            j += 1; // the opening quote
            loop {
                if b[j] == b'"'
                    && b[j + 1..]
                        .iter()
                        .take(hashes)
                        .filter(|&&h| h == b'#')
                        .count()
                        == hashes
                {
                    break;
                }
                j += 1;
            }
            i = j + 1 + hashes;
            out.push_str("\"\"");
        } else if c == b'"' {
            let mut j = i + 1;
            while b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            i = j + 1;
            out.push_str("\"\"");
        } else if c == b'\'' {
            // a character literal ('x', '\n', '\u{1F}', multi-byte), else a lifetime
            let rest = &src[i + 1..];
            let len = if let Some(esc) = rest.strip_prefix('\\') {
                esc.find('\'').map(|k| k + 1)
            } else {
                rest.chars()
                    .next()
                    .filter(|ch| rest[ch.len_utf8()..].starts_with('\''))
                    .map(|ch| ch.len_utf8())
            };
            match len {
                Some(k) => {
                    i += k + 2;
                    out.push_str("' '");
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            let ch = src[i..].chars().next().unwrap();
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    out
}

fn raw_start(b: &[u8]) -> bool {
    let b = b.strip_prefix(b"b").unwrap_or(b);
    let Some(mut b) = b.strip_prefix(b"r") else {
        return false;
    };
    while let Some(r) = b.strip_prefix(b"#") {
        b = r;
    }
    b.first() == Some(&b'"')
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Path,
    Open,
    Close,
    Comma,
    Semi,
    Star,
    Hash,
    Other,
}

fn tokens(code: &str) -> Vec<Tok> {
    let mut out = Vec::new();
    let mut it = code.char_indices().peekable();
    while let Some((i, c)) = it.next() {
        if c.is_alphanumeric() || c == '_' {
            let mut end = i + c.len_utf8();
            while let Some(&(j, d)) = it.peek() {
                if d.is_alphanumeric() || d == '_' {
                    end = j + d.len_utf8();
                    it.next();
                } else {
                    break;
                }
            }
            out.push(Tok::Ident(code[i..end].to_string()));
        } else if c == ':' && it.peek().map(|p| p.1) == Some(':') {
            it.next();
            out.push(Tok::Path);
        } else {
            out.push(match c {
                '{' => Tok::Open,
                '}' => Tok::Close,
                ',' => Tok::Comma,
                ';' => Tok::Semi,
                '*' => Tok::Star,
                '#' => Tok::Hash,
                c if c.is_whitespace() => continue,
                _ => Tok::Other,
            });
        }
    }
    out
}

/// The tokens with every `#[cfg(test)]` item (a test module or function) removed.
fn without_tests(t: Vec<Tok>) -> Vec<Tok> {
    let id = |s: &str| Tok::Ident(s.to_string());
    let mut out = Vec::new();
    let mut i = 0;
    while i < t.len() {
        // # [ cfg ( test ) ] → Hash Other Ident(cfg) Other Ident(test) Other Other
        if t[i] == Tok::Hash
            && t.get(i + 2) == Some(&id("cfg"))
            && t.get(i + 4) == Some(&id("test"))
        {
            let mut j = i + 7;
            while j < t.len() && t[j] != Tok::Open && t[j] != Tok::Semi {
                j += 1;
            }
            if j < t.len() && t[j] == Tok::Open {
                let mut depth = 0;
                while j < t.len() {
                    match t[j] {
                        Tok::Open => depth += 1,
                        Tok::Close => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                    j += 1;
                }
            }
            i = j + 1;
        } else {
            out.push(t[i].clone());
            i += 1;
        }
    }
    out
}

/// The start of a path (`crate`, `super`…, `self`) as an absolute module path in `module`.
fn anchor(module: &[String], t: &[Tok], mut i: usize) -> Option<(Module, usize)> {
    let Tok::Ident(first) = &t[i] else {
        return None;
    };
    let mut base: Module = match first.as_str() {
        "crate" => Vec::new(),
        "self" => module.to_vec(),
        "super" => module[..module.len().saturating_sub(1)].to_vec(),
        _ => return None,
    };
    i += 1;
    while t.get(i) == Some(&Tok::Path) && t.get(i + 1) == Some(&Tok::Ident("super".into())) {
        base.pop();
        i += 2;
    }
    (t.get(i) == Some(&Tok::Path)).then_some((base, i))
}

/// Expand a use tree starting at `t[i]` (just after a `::`) under `prefix` into paths; returns
/// the index after it.
fn use_tree(t: &[Tok], mut i: usize, prefix: Module, out: &mut Vec<Module>) -> usize {
    let mut path = prefix;
    loop {
        match t.get(i) {
            Some(Tok::Ident(s)) if s != "as" => {
                if s != "self" {
                    path.push(s.clone());
                }
                i += 1;
                if t.get(i) == Some(&Tok::Path) {
                    i += 1;
                    continue;
                }
                out.push(path);
                if t.get(i) == Some(&Tok::Ident("as".into())) {
                    i += 2;
                }
                return i;
            }
            Some(Tok::Open) => {
                i += 1;
                while i < t.len() && t[i] != Tok::Close {
                    if t[i] == Tok::Comma {
                        i += 1;
                        continue;
                    }
                    i = use_tree(t, i, path.clone(), out);
                }
                return i + 1;
            }
            Some(Tok::Star) => {
                out.push(path);
                return i + 1;
            }
            _ => {
                out.push(path);
                return i;
            }
        }
    }
}

/// Every crate path named in `code` (a file of `module`), absolute; the second list holds the
/// paths of `pub use` items (re-exports).
fn references(module: &[String], code: &str) -> (Vec<Module>, Vec<Module>) {
    references_in(module, &without_tests(tokens(&lex(code))))
}

/// [`references`] in the tokens `t`.
fn references_in(module: &[String], t: &[Tok]) -> (Vec<Module>, Vec<Module>) {
    let (mut all, mut reexports) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < t.len() {
        let is_use = t[i] == Tok::Ident("use".into());
        let start = if is_use { i + 1 } else { i };
        let anchored = t.get(start).and_then(|_| anchor(module, t, start));
        // `use child::…` without an anchor names a child of this module (or an external
        // crate, which resolves to this file itself)
        let relative = || match (is_use, t.get(start)) {
            (true, Some(Tok::Ident(_))) => Some((module.to_vec(), start - 1)),
            _ => None,
        };
        let Some((base, j)) = anchored.or_else(relative) else {
            i += 1;
            continue;
        };
        let mut found = Vec::new();
        let end = if is_use {
            use_tree(t, j + 1, base, &mut found)
        } else {
            let (mut p, mut k) = (base, j);
            while t.get(k) == Some(&Tok::Path) {
                match t.get(k + 1) {
                    Some(Tok::Ident(s)) => p.push(s.clone()),
                    _ => break,
                }
                k += 2;
            }
            found.push(p);
            k
        };
        let public = is_use && i > 0 && matches!(&t[i - 1], Tok::Ident(s) if s == "pub");
        if public {
            reexports.extend(found.iter().cloned());
        }
        all.extend(found);
        i = end.max(i + 1);
    }
    (all, reexports)
}

/// The modules a crate root (lib.rs, main.rs) declares: `mod x;`, `pub mod x;`, `pub(crate) mod
/// x;` outside comments and `#[cfg(test)]` items.
fn declared_modules(root_file: &str) -> BTreeSet<String> {
    let t = without_tests(tokens(&lex(root_file)));
    let mut out = BTreeSet::new();
    for i in 0..t.len().saturating_sub(2) {
        if let (Tok::Ident(m), Tok::Ident(name), Tok::Semi) = (&t[i], &t[i + 1], &t[i + 2]) {
            if m == "mod" {
                out.insert(name.clone());
            }
        }
    }
    out
}

/// The library's files: module path → source text (`lib.rs` and `main.rs` are not modules, and
/// the binary's modules — those src/main.rs declares — are not the library's).
fn read_src(root: &Path) -> BTreeMap<Module, String> {
    let binary = declared_modules(&std::fs::read_to_string(root.join("main.rs")).unwrap());
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(root).unwrap().with_extension("");
                let mut m: Module = rel
                    .iter()
                    .map(|s| s.to_string_lossy().into_owned())
                    .collect();
                if m.last().is_some_and(|s| s == "mod") {
                    m.pop();
                }
                // unit tests in a file of their own (`#[cfg(test)] mod tests;`), like the
                // inline `#[cfg(test)]` modules, are not part of the graph
                if m == ["lib"]
                    || m == ["main"]
                    || m.last().is_some_and(|s| s == "tests")
                    || binary.contains(&m[0])
                {
                    continue;
                }
                out.insert(m, std::fs::read_to_string(&p).unwrap());
            }
        }
    }
    out
}

/// The file graph (module paths joined by `::`) and the top-level graph of `files`.
fn graphs(files: &BTreeMap<Module, String>) -> (Graph, Graph) {
    let refs: BTreeMap<&Module, (Vec<Module>, Vec<Module>)> = files
        .iter()
        .map(|(m, code)| (m, references(m, code)))
        .collect();
    // name exported by a module file → the path it re-exports
    let mut exports: BTreeMap<(Module, String), Module> = BTreeMap::new();
    for (m, (_, re)) in &refs {
        for p in re {
            if let Some(last) = p.last() {
                exports.insert(((*m).clone(), last.clone()), p.clone());
            }
        }
    }
    let resolve = |p: &Module| -> Option<Module> {
        let mut p = p.clone();
        for _ in 0..8 {
            let n = (1..=p.len()).rev().find(|&n| files.contains_key(&p[..n]))?;
            let file = p[..n].to_vec();
            match p
                .get(n)
                .and_then(|name| exports.get(&(file.clone(), name.clone())))
            {
                Some(target) if target[..] != p[..n + 1] => {
                    let mut next = target.clone();
                    next.extend_from_slice(&p[n + 1..]);
                    p = next;
                }
                _ => return Some(file),
            }
        }
        None
    };
    let (mut file_graph, mut top) = (Graph::new(), Graph::new());
    for (m, (all, _)) in &refs {
        let from = m.join("::");
        file_graph.entry(from.clone()).or_default();
        for p in all {
            if let Some(first) = p.first() {
                if files.keys().any(|k| k.first() == Some(first)) && *first != m[0] {
                    top.entry(m[0].clone()).or_default().insert(first.clone());
                }
            }
            let Some(to) = resolve(p) else { continue };
            if !m.starts_with(&to) {
                file_graph
                    .entry(from.clone())
                    .or_default()
                    .insert(to.join("::"));
            }
        }
    }
    (file_graph, top)
}

/// The strongly connected components of more than one node (Tarjan), each sorted.
fn cycles(g: &Graph) -> Vec<Vec<String>> {
    struct S<'a> {
        g: &'a Graph,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut S<'a>, v: &'a str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        for w in s.g.get(v).into_iter().flatten() {
            if !s.index.contains_key(w.as_str()) {
                visit(s, w);
                let lw = s.low[w.as_str()];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.stack.contains(&w.as_str()) {
                let iw = s.index[w.as_str()];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = S {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// Each cycle with the edges inside it, for the failure message.
fn explain(g: &Graph, cycles: &[Vec<String>]) -> String {
    let mut msg = String::new();
    for c in cycles {
        msg.push_str(&format!("cycle {c:?}:\n"));
        for a in c {
            let inside: Vec<&String> = g[a].iter().filter(|b| c.contains(b)).collect();
            msg.push_str(&format!("  {a} -> {inside:?}\n"));
        }
    }
    msg
}

fn src_graphs() -> (Graph, Graph) {
    graphs(&read_src(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
    ))
}

#[test]
fn top_level_modules_import_each_other_without_a_cycle() {
    let (_, top) = src_graphs();
    assert!(top.len() > 10, "too few modules parsed: {top:?}");
    let c = cycles(&top);
    assert!(c.is_empty(), "{}", explain(&top, &c));
}

/// File cycles accepted for now (none): the test fails on any cycle, and on a listed one that
/// is gone.
const OPEN_FILE_CYCLES: &[&[&str]] = &[];

#[test]
fn files_import_each_other_without_a_cycle() {
    let (files, _) = src_graphs();
    assert!(files.len() > 100, "too few files parsed: {}", files.len());
    let c = cycles(&files);
    let found: BTreeSet<Vec<String>> = c.iter().cloned().collect();
    assert_eq!(found, set(OPEN_FILE_CYCLES), "{}", explain(&files, &c));
}

fn src_file(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src").join(name)).unwrap()
}

#[test]
fn the_command_line_is_the_binarys_not_the_librarys() {
    let lib = declared_modules(&src_file("lib.rs"));
    let bin = declared_modules(&src_file("main.rs"));
    assert!(
        lib.contains("lp") && lib.len() > 10,
        "lib.rs not parsed: {lib:?}"
    );
    assert!(
        !lib.contains("cli"),
        "the library declares a cli module: {lib:?}"
    );
    assert!(
        bin.contains("cli"),
        "src/main.rs declares no cli module: {bin:?}"
    );
    let shared: Vec<&String> = lib.intersection(&bin).collect();
    assert!(
        shared.is_empty(),
        "modules in both the library and the binary: {shared:?}"
    );
    // no library file names the command line, and the command line reaches the library only as
    // `momentlab::…` (a `crate::` path of a binary file names the binary's own modules)
    let (files, _) = src_graphs();
    let users: Vec<String> = files
        .keys()
        .filter(|f| f.split("::").any(|part| part == "cli"))
        .cloned()
        .collect();
    assert!(
        users.is_empty(),
        "library files of the command line: {users:?}"
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut uses_library = false;
    for m in &bin {
        let dir = root.join(m);
        let paths = if dir.is_dir() {
            rust_files(&dir)
        } else {
            vec![root.join(format!("{m}.rs"))]
        };
        for p in paths {
            let code = std::fs::read_to_string(&p).unwrap();
            let t = without_tests(tokens(&lex(&code)));
            for w in t.windows(3) {
                if let (Tok::Ident(a), Tok::Path, Tok::Ident(b)) = (&w[0], &w[1], &w[2]) {
                    uses_library |= a == "momentlab";
                    assert!(
                        a != "crate" || bin.contains(b),
                        "{}: crate::{b} in the binary (the library is momentlab::{b})",
                        p.display()
                    );
                }
            }
        }
    }
    assert!(uses_library, "the binary's modules were not parsed");
    let (_, top) = src_graphs();
    let users: Vec<&String> = top
        .iter()
        .filter(|(_, to)| to.iter().any(|t| bin.contains(t)))
        .map(|(m, _)| m)
        .collect();
    assert!(
        users.is_empty(),
        "library modules importing the binary: {users:?}"
    );
}

/// The library's top-level modules in the order of the data flow (src/lib.rs): foundations,
/// then depth stacks and rendering, filtering, the moment problem and the techniques, the
/// error against PCF (and the eye views built on it), the studies built on it, the GPU path
/// that runs their settings, and the reports. A module imports only modules
/// of earlier layers or of its own (within a layer the graph is acyclic, checked above).
const LAYERS: &[&[&str]] = &[
    &["artefact", "progress", "grid", "linalg"],
    &["lp"],
    &["basis", "bench"],
    &["shader"],
    &["technique"],
    &["stack", "render"],
    &["kernel"],
    &["metrics"],
    &["quantize", "stability"],
    &["search", "tune"],
    &["gpu"],
    &["batch", "report"],
    &["pipeline"],
];

fn layer_of(m: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&m))
}

#[test]
fn top_level_modules_never_import_a_later_layer() {
    let (_, top) = src_graphs();
    let lib = declared_modules(&src_file("lib.rs"));
    let unlisted: Vec<&String> = lib.iter().filter(|m| layer_of(m).is_none()).collect();
    assert!(
        unlisted.is_empty(),
        "modules missing from LAYERS: {unlisted:?}"
    );
    let stale: Vec<&&str> = LAYERS
        .iter()
        .flat_map(|l| l.iter())
        .filter(|m| !lib.contains(**m))
        .collect();
    assert!(
        stale.is_empty(),
        "LAYERS names modules lib.rs lacks: {stale:?}"
    );
    let mut back = Vec::new();
    for (from, to) in &top {
        for t in to {
            if let (Some(a), Some(b)) = (layer_of(from), layer_of(t)) {
                if b > a {
                    back.push(format!("{from} (layer {a}) -> {t} (layer {b})"));
                }
            }
        }
    }
    assert!(back.is_empty(), "backward arrows:\n{}", back.join("\n"));
    assert!(
        top["render"].contains("stack") || top["metrics"].contains("stack"),
        "imports were not parsed: {top:?}"
    );
}

/// Imports of a later layer made by unit tests (`#[cfg(test)]` items, `tests.rs` files), kept
/// for now: (file under src/, module imported, why). The test fails on any other, and on a
/// listed one that is gone.
const TEST_BACKWARD_IMPORTS: &[(&str, &str, &str)] = &[];

#[test]
fn unit_tests_import_a_later_layer_only_where_listed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = declared_modules(&src_file("lib.rs"));
    let mut found = BTreeSet::new();
    for p in rust_files(&root) {
        let rel = p
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let mut m: Module = rel
            .trim_end_matches(".rs")
            .split('/')
            .map(str::to_string)
            .collect();
        if !lib.contains(&m[0]) {
            continue;
        }
        if m.last().is_some_and(|s| s == "mod") {
            m.pop();
        }
        let code = std::fs::read_to_string(&p).unwrap();
        let (all, _) = references_in(&m, &tokens(&lex(&code)));
        for to in all.iter().filter_map(|q| q.first()) {
            if let (Some(a), Some(b)) = (layer_of(&m[0]), layer_of(to)) {
                if b > a {
                    found.insert((rel.clone(), to.clone()));
                }
            }
        }
    }
    let listed: BTreeSet<(String, String)> = TEST_BACKWARD_IMPORTS
        .iter()
        .map(|&(f, to, _)| (f.to_string(), to.to_string()))
        .collect();
    assert_eq!(
        found, listed,
        "imports of a later layer in src/ (test code included) against TEST_BACKWARD_IMPORTS"
    );
}

fn module(s: &str) -> Module {
    s.split("::").map(str::to_string).collect()
}

fn sources(list: &[(&str, &str)]) -> BTreeMap<Module, String> {
    list.iter()
        .map(|(m, code)| (module(m), code.to_string()))
        .collect()
}

fn set(list: &[&[&str]]) -> BTreeSet<Vec<String>> {
    list.iter()
        .map(|c| c.iter().map(|s| s.to_string()).collect())
        .collect()
}

#[test]
fn a_planted_cycle_is_found_and_an_acyclic_graph_passes() {
    let edges = |list: &[(&str, &str)]| {
        let mut g = Graph::new();
        for (a, b) in list {
            g.entry(a.to_string()).or_default().insert(b.to_string());
            g.entry(b.to_string()).or_default();
        }
        g
    };
    let dag = edges(&[("a", "b"), ("b", "c"), ("a", "c"), ("d", "a")]);
    assert!(cycles(&dag).is_empty());
    let planted = edges(&[
        ("a", "b"),
        ("b", "c"),
        ("c", "a"),
        ("d", "a"),
        ("e", "f"),
        ("f", "e"),
    ]);
    let found: BTreeSet<Vec<String>> = cycles(&planted).into_iter().collect();
    assert_eq!(found, set(&[&["a", "b", "c"], &["e", "f"]]));
}

#[test]
fn planted_source_cycles_are_found_through_use_trees_super_and_reexports() {
    // files of a small crate: x::one → x::two by a `super::` use tree, x::two → x::one through
    // x's re-export; y → z by a path in code, z → y by a grouped `crate::{…}` use
    let files = sources(&[
        (
            "x",
            "pub mod one; pub mod two; pub use one::Thing; pub struct Local;",
        ),
        (
            "x::one",
            "use super::{two::{self, Other as O}, *};\npub struct Thing;",
        ),
        (
            "x::two",
            "use crate::x::Thing; // crate::y::Nothing in a comment\npub struct Other;",
        ),
        (
            "y",
            "fn f() { let s = \"crate::z::in_a_string\"; crate::z::g(); }",
        ),
        (
            "z",
            "use crate::{w, y::{self}};\n#[cfg(test)]\nmod tests { use crate::q; }",
        ),
        ("w", "pub fn lifetime<'a>(c: char) -> bool { c == '{' }"),
        ("q", "use crate::w;"),
    ]);
    let (file_graph, top) = graphs(&files);
    assert_eq!(file_graph["x::one"], ["x::two".to_string()].into());
    assert_eq!(file_graph["x::two"], ["x::one".to_string()].into());
    assert_eq!(file_graph["y"], ["z".to_string()].into());
    assert_eq!(file_graph["z"], ["w".to_string(), "y".to_string()].into());
    assert!(file_graph["w"].is_empty());
    let found: BTreeSet<Vec<String>> = cycles(&file_graph).into_iter().collect();
    assert_eq!(found, set(&[&["x::one", "x::two"], &["y", "z"]]));
    let found: BTreeSet<Vec<String>> = cycles(&top).into_iter().collect();
    assert_eq!(found, set(&[&["y", "z"]]));
    // a child naming its parent's own items is no cycle; without the back edges both clear
    let mut acyclic = files.clone();
    acyclic.insert(
        module("x::two"),
        "use super::Local as L; pub struct Other;".into(),
    );
    acyclic.insert(module("z"), "use crate::w;".into());
    let (file_graph, top) = graphs(&acyclic);
    assert!(cycles(&file_graph).is_empty(), "{file_graph:?}");
    assert!(cycles(&top).is_empty(), "{top:?}");
}

/// `src` with comments and the contents of string and character literals blanked to spaces:
/// the same length and the same lines, so positions in it are positions in the file.
fn blank(src: &str) -> Vec<u8> {
    let mut b = src.as_bytes().to_vec();
    let mut i = 0;
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let clear = |b: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut b[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            let e = b[i..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(b.len(), |p| i + p);
            clear(&mut b, i, e);
            i = e;
        } else if b[i..].starts_with(b"/*") {
            let (mut depth, mut j) = (0, i);
            while j < b.len() {
                if b[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if b[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            clear(&mut b, i, j);
            i = j;
        } else if (b[i] == b'r' || (b[i] == b'b' && b.get(i + 1) == Some(&b'r')))
            && (i == 0 || !ident(b[i - 1]))
            && {
                let k = i + 1 + usize::from(b[i] == b'b');
                let h = b[k..].iter().take_while(|&&c| c == b'#').count();
                b.get(k + h) == Some(&b'"')
            }
        {
            let k = i + 1 + usize::from(b[i] == b'b');
            let h = b[k..].iter().take_while(|&&c| c == b'#').count();
            let mut close = vec![b'"'];
            close.extend(std::iter::repeat_n(b'#', h));
            let start = k + h + 1;
            let e = b[start..]
                .windows(close.len())
                .position(|w| w == close.as_slice())
                .map_or(b.len(), |p| start + p);
            clear(&mut b, start, e);
            i = e + close.len();
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            let j = j.min(b.len());
            clear(&mut b, i + 1, j);
            i = j + 1;
        } else if b[i] == b'\'' {
            // a char literal ('x', '\n', '\u{..}', '{') or a lifetime ('a)
            let j = if b.get(i + 1) == Some(&b'\\') {
                b[i + 3..]
                    .iter()
                    .position(|&c| c == b'\'')
                    .map(|p| i + 3 + p)
            } else {
                let len = src[i + 1..].chars().next().map_or(1, char::len_utf8);
                (b.get(i + 1 + len) == Some(&b'\'')).then_some(i + 1 + len)
            };
            match j {
                Some(j) => {
                    clear(&mut b, i + 1, j);
                    i = j + 1;
                }
                None => i += 1,
            }
        } else {
            i += 1;
        }
    }
    b
}

/// (name, first line, number of lines) of every `fn` with a body in `src`, from the `fn`
/// line to its closing brace.
fn function_lengths(src: &str) -> Vec<(String, usize, usize)> {
    let b = blank(src);
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let line = |p: usize| b[..p].iter().filter(|&&c| c == b'\n').count() + 1;
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(p) = b[i..].windows(3).position(|w| w == b"fn ") {
        let at = i + p;
        i = at + 3;
        if at > 0 && ident(b[at - 1]) {
            continue;
        }
        let name: String = b[i..]
            .iter()
            .take_while(|&&c| ident(c))
            .map(|&c| c as char)
            .collect();
        if name.is_empty() {
            continue;
        }
        // the body's `{`, unless a `;` (a declaration) comes first, outside () and []
        let mut nest = 0i32;
        let Some(q) = b[i..].iter().position(|&c| {
            match c {
                b'(' | b'[' => nest += 1,
                b')' | b']' => nest -= 1,
                _ => {}
            }
            nest == 0 && (c == b'{' || c == b';')
        }) else {
            break;
        };
        if b[i + q] == b';' {
            continue;
        }
        let (mut depth, mut j) = (0usize, i + q);
        while j < b.len() {
            match b[j] {
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
        out.push((name, line(at), line(j) - line(at) + 1));
    }
    out
}

/// Longest function allowed in src/ (lines from `fn` to its closing brace).
const MAX_FUNCTION_LINES: usize = 120;

/// Functions over [`MAX_FUNCTION_LINES`] kept as they are: (file under src/, function, why).
const LONG_FUNCTIONS: &[(&str, &str, &str)] = &[
    (
        "tune/export/tmsm.rs",
        "tmsm_into",
        "generated transcript: the TMSM evaluation written out straight-line for the shader IR",
    ),
    (
        "shader/print.rs",
        "func",
        "one match over the IR's statements, printed in order (GLSL/HLSL)",
    ),
    (
        "shader/wgsl.rs",
        "func",
        "one match over the IR's statements, printed in order (WGSL)",
    ),
];

/// Largest file of src/lp/ in lines: each mechanism of the LP in a file a reader can hold.
const MAX_LP_FILE_LINES: usize = 800;

fn rust_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn no_file_of_src_lp_is_over_800_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = rust_files(&root.join("src/lp"));
    assert!(files.len() > 20, "too few files: {files:?}");
    let long: Vec<String> = files
        .iter()
        .map(|p| (p, std::fs::read_to_string(p).unwrap().lines().count()))
        .filter(|&(_, n)| n > MAX_LP_FILE_LINES)
        .map(|(p, n)| format!("{} ({n} lines)", p.strip_prefix(root).unwrap().display()))
        .collect();
    assert!(long.is_empty(), "over {MAX_LP_FILE_LINES} lines: {long:?}");
}

#[test]
fn no_function_of_src_is_over_120_lines_but_the_listed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut long = BTreeSet::new();
    let mut report = Vec::new();
    for p in rust_files(&root) {
        let rel = p
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        for (name, at, n) in function_lengths(&std::fs::read_to_string(&p).unwrap()) {
            if n > MAX_FUNCTION_LINES {
                long.insert((rel.clone(), name.clone()));
                if !LONG_FUNCTIONS
                    .iter()
                    .any(|&(f, g, _)| f == rel && g == name)
                {
                    report.push(format!("src/{rel}:{at} {name} ({n} lines)"));
                }
            }
        }
    }
    assert!(
        report.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines:\n{}",
        report.join("\n")
    );
    let stale: Vec<_> = LONG_FUNCTIONS
        .iter()
        .filter(|&&(f, g, _)| !long.contains(&(f.to_string(), g.to_string())))
        .collect();
    assert!(stale.is_empty(), "listed but no longer long: {stale:?}");
}

/// The scanner finds functions by their braces, not by braces in strings, chars or comments.
#[test]
fn function_lengths_skip_braces_in_strings_chars_and_comments() {
    let src = "fn a() {\n    let s = \"}}\"; // }\n    let c = '}';\n    /* } */\n}\n\
               trait T { fn decl(&self, a: [u8; 2]); }\nfn b<'x>(v: &'x str) -> &'x str {\n    \
               let r = r#\"}\"#;\n    v\n}\nfn c(x: [f64; 3]) {\n}\n";
    let got = function_lengths(src);
    assert_eq!(
        got,
        vec![
            ("a".to_string(), 1, 5),
            ("b".to_string(), 7, 4),
            ("c".to_string(), 11, 2)
        ],
        "{src}"
    );
}
