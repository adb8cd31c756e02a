//! The shape of `driver/src`: no import cycle between its top-level modules, and no scene kind importing
//! another. Read from the source text (every `crate::…` path outside comments, and `super::super` climbing out
//! of a kind's folder), so it checks what the compiler would link, without extra tools. Run alone with
//! `cargo test -p lbdem --test integration architecture::`.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
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

#[test]
fn top_level_modules_form_no_import_cycle() {
    let g = graph();
    // Kahn's algorithm: repeatedly remove modules that use no remaining module.
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
            "import cycle among the modules of driver/src: {left:?}"
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
