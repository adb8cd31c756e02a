//! The shape of `driver/src`: no import cycle between its top-level modules, nor between the sibling modules
//! of any folder (`engine::exec` ↔ `engine::lattice` would be one), and no scene kind importing another. Read from the source text (every `crate::…` path outside comments, and `super::super` climbing out
//! of a kind's folder), so it checks what the compiler would link, without extra tools. Run alone with
//! `cargo test -p lbdem --test integration architecture::`.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    out.extend(crate::common::files_with_extension(dir, "rs"));
}

/// The code of a file without its comments (line comments, doc comments).
fn code(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| match l.find("//") {
            // Keep "//" inside string literals such as URLs: only cut when no quote precedes it.
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every `crate::name` the code refers to (the first path segment after `crate::`).
fn crate_refs(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        let tail = &rest[i + 7..];
        let name: String = tail
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if !name.is_empty() {
            out.insert(name);
        }
        rest = &rest[i + 7..];
    }
    out
}

/// The top-level module a file belongs to (`engine` for `src/engine/dem/world.rs`, `units` for `src/units.rs`).
fn top_module(path: &Path) -> Option<String> {
    let rel = path.strip_prefix(src()).unwrap();
    let first = rel
        .components()
        .next()?
        .as_os_str()
        .to_string_lossy()
        .into_owned();
    let name = first.trim_end_matches(".rs").to_string();
    (name != "lib" && name != "main").then_some(name)
}

/// Module → modules it uses.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let Some(m) = top_module(&f) else { continue };
        let refs = crate_refs(&code(&f));
        let e = g.entry(m.clone()).or_default();
        e.extend(refs.into_iter().filter(|r| *r != m));
    }
    g
}

/// The modules of `g` in an order where each uses only earlier ones (Kahn's algorithm: repeatedly remove the
/// modules that use no remaining module; uses of modules outside `g` are ignored); panics naming the modules
/// left when they form a cycle.
fn acyclic_order(g: &BTreeMap<String, BTreeSet<String>>, what: &str) -> Vec<String> {
    let mut left: BTreeMap<String, BTreeSet<String>> = g
        .iter()
        .map(|(m, deps)| {
            let deps = deps
                .iter()
                .filter(|d| g.contains_key(*d))
                .cloned()
                .collect();
            (m.clone(), deps)
        })
        .collect();
    let mut order = Vec::new();
    while !left.is_empty() {
        let ready: Vec<String> = left
            .iter()
            .filter(|(_, deps)| deps.is_empty())
            .map(|(m, _)| m.clone())
            .collect();
        assert!(
            !ready.is_empty(),
            "import cycle among the modules of {what}: {left:?}"
        );
        for m in &ready {
            left.remove(m);
        }
        for deps in left.values_mut() {
            for m in &ready {
                deps.remove(m);
            }
        }
        order.extend(ready);
    }
    order
}

#[test]
fn top_level_modules_form_no_import_cycle() {
    let g = graph();
    let order = acyclic_order(&g, "driver/src");
    // The layers the architecture asks for (docs/architecture.md): the engine knows no scenes, runs or files.
    for (lower, upper) in [
        ("engine", "scene"),
        ("engine", "run"),
        ("engine", "output"),
        ("engine", "kinds"),
        ("engine", "observe"),
        ("units", "engine"),
        ("run", "kinds"),
        ("observe", "kinds"),
        ("output", "kinds"),
        ("scene", "kinds"),
    ] {
        assert!(
            !g.get(lower).is_some_and(|d| d.contains(upper)),
            "{lower} must not use {upper}"
        );
    }
    eprintln!("driver/src layers, lowest first: {order:?}");
}

/// The module path of a file of the library (`["engine", "lattice"]` for `src/engine/lattice.rs` and for
/// `src/engine/lattice/mod.rs`); `None` for the binary's files (`main.rs`), which form another crate.
fn module_path(path: &Path) -> Option<Vec<String>> {
    let rel = path.strip_prefix(src()).unwrap();
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = parts.pop()?;
    let stem = last.trim_end_matches(".rs");
    match stem {
        "main" if parts.is_empty() => return None,
        "lib" if parts.is_empty() => {}
        "mod" => {}
        _ => parts.push(stem.to_string()),
    }
    Some(parts)
}

/// The paths of one `use` tree or path expression starting at `s[*i]` (after `crate::`, `super::` or `self::`),
/// each as its segments, appended to `prefix`: `{exec::{a, b}, lattice::C as D}` gives `exec::a`, `exec::b`,
/// `lattice::C`.
fn use_tree(s: &[u8], i: &mut usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut prefix = prefix;
    loop {
        while *i < s.len() && s[*i].is_ascii_whitespace() {
            *i += 1;
        }
        if *i < s.len() && s[*i] == b'{' {
            *i += 1;
            loop {
                while *i < s.len() && (s[*i].is_ascii_whitespace() || s[*i] == b',') {
                    *i += 1;
                }
                if *i >= s.len() || s[*i] == b'}' {
                    *i += 1;
                    return;
                }
                use_tree(s, i, prefix.clone(), out);
                // Skip a renaming (`as D`) up to the next item.
                while *i < s.len() && s[*i] != b',' && s[*i] != b'}' && s[*i] != b'{' {
                    *i += 1;
                }
            }
        }
        let start = *i;
        while *i < s.len() && (s[*i].is_ascii_alphanumeric() || s[*i] == b'_' || s[*i] == b'*') {
            *i += 1;
        }
        if *i > start {
            prefix.push(String::from_utf8_lossy(&s[start..*i]).into_owned());
        }
        if *i > start && s[*i..].starts_with(b"::") {
            *i += 2;
            continue;
        }
        out.push(prefix);
        return;
    }
}

/// Every module path the code of the file at module path `here` refers to through `crate::`, `super::` or
/// `self::` (resolved to absolute paths). The file's test module (from `#[cfg(test)]` on) is left out: its
/// `super::` means the file itself.
fn refs(code: &str, here: &[String]) -> Vec<Vec<String>> {
    let code = match code.find("#[cfg(test)]\nmod ") {
        Some(k) => &code[..k],
        None => code,
    };
    let s = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let boundary =
            i == 0 || !(s[i - 1].is_ascii_alphanumeric() || s[i - 1] == b'_' || s[i - 1] == b':');
        let head = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|h| s[i..].starts_with(h.as_bytes()));
        match head {
            Some(_) if boundary => {
                let mut paths = Vec::new();
                use_tree(s, &mut i, Vec::new(), &mut paths);
                for p in paths {
                    let mut base: Vec<String> = here.to_vec();
                    let mut k = 0;
                    match p.first().map(String::as_str) {
                        Some("crate") => {
                            base.clear();
                            k = 1;
                        }
                        Some("self") => k = 1,
                        _ => {
                            while p.get(k).is_some_and(|x| x == "super") {
                                base.pop();
                                k += 1;
                            }
                        }
                    }
                    base.extend(p[k..].iter().cloned());
                    out.push(base);
                }
            }
            _ => i += 1,
        }
    }
    out
}

#[test]
fn sibling_modules_form_no_import_cycle_at_any_depth() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let files: Vec<(Vec<String>, String)> = files
        .iter()
        .filter_map(|f| Some((module_path(f)?, code(f))))
        .collect();
    // Every module that has children: its children are the siblings checked against each other.
    let parents: BTreeSet<Vec<String>> = files
        .iter()
        .filter(|(m, _)| !m.is_empty())
        .map(|(m, _)| m[..m.len() - 1].to_vec())
        .collect();
    let mut checked = 0;
    for parent in &parents {
        let depth = parent.len();
        let children: BTreeSet<String> = files
            .iter()
            .filter(|(m, _)| m.len() > depth && m.starts_with(parent))
            .map(|(m, _)| m[depth].clone())
            .collect();
        let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (m, code) in files
            .iter()
            .filter(|(m, _)| m.len() > depth && m.starts_with(parent))
        {
            let from = &m[depth];
            let e = g.entry(from.clone()).or_default();
            for r in refs(code, m) {
                if r.len() > depth
                    && r.starts_with(parent)
                    && r[depth] != *from
                    && children.contains(&r[depth])
                {
                    e.insert(r[depth].clone());
                }
            }
        }
        acyclic_order(&g, &format!("`crate::{}`", parent.join("::")));
        checked += 1;
    }
    // The library root, engine, engine::dem, kinds, every kind with sub-files, …: a test that read no folder
    // would pass vacuously.
    assert!(
        checked >= 8,
        "only {checked} module folders read: {parents:?}"
    );
}

#[test]
fn the_path_reader_sees_grouped_and_relative_imports() {
    let here: Vec<String> = vec!["engine".into(), "dem".into(), "loading".into()];
    let code = "use super::{packing::Packing, staged::{A, B as C}};\nuse crate::engine::exec::X;\n\
                let _ = super::super::lattice::Streaming::Aa; pub(super) fn f() {}";
    let got: BTreeSet<String> = refs(code, &here)
        .into_iter()
        .map(|p| p.join("::"))
        .collect();
    for want in [
        "engine::dem::packing::Packing",
        "engine::dem::staged::A",
        "engine::dem::staged::B",
        "engine::exec::X",
        "engine::lattice::Streaming::Aa",
    ] {
        assert!(got.contains(want), "{want} not in {got:?}");
    }
}

#[test]
fn no_kind_imports_another() {
    let kinds = src().join("kinds");
    let names: Vec<String> = std::fs::read_dir(&kinds)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(names.len() >= 10, "the kinds: {names:?}");
    for kind in &names {
        let mut files = Vec::new();
        rust_files(&kinds.join(kind), &mut files);
        for f in files {
            let code = code(&f);
            for other in names.iter().filter(|o| *o != kind) {
                assert!(
                    !code.contains(&format!("kinds::{other}")),
                    "{} uses the kind `{other}`",
                    f.display()
                );
            }
            // Climbing out of the kind's folder would reach the registry or a sibling kind: `super::super` from
            // any of its files (or from a test module of its mod.rs), or a top-level `super::` in its mod.rs.
            let top_level_super =
                f.ends_with("mod.rs") && code.lines().any(|l| l.starts_with("use super::"));
            assert!(
                !code.contains("super::super") && !top_level_super,
                "{} reaches above its kind's folder",
                f.display()
            );
        }
    }
}
