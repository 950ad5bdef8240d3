//! The module graph (issue 43): no import circle between the core's modules, so the file list
//! reads as floors (each module opens with the part of the paper it implements); and in
//! `host-sim`, no study (what a command runs) imports another, and no floor imports a study.
//! Read from the sources: `crate::` paths outside comments and test modules.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, with its module path relative to `dir` (`a/b.rs` and
/// `a/b/mod.rs` are `a::b`).
fn sources(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(dir).unwrap().with_extension("");
                let mut parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                if parts.last().is_some_and(|l| l == "mod") {
                    parts.pop();
                }
                out.push((parts.join("::"), p));
            }
        }
    }
    out.sort();
    out
}

/// The `crate::a::b` paths a file names outside comments and its test module, each as its
/// segments.
fn imports(file: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(file).unwrap();
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    let mut out = Vec::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        let mut rest = line;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            let path: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            out.push(
                path.split("::")
                    .filter(|s| !s.is_empty())
                    .map(str::to_string)
                    .collect(),
            );
        }
    }
    out
}

/// A circle in `graph`, if any (depth-first search).
fn circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        v: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(v.to_string(), 1);
        path.push(v.to_string());
        for w in g.get(v).into_iter().flatten() {
            match state.get(w.as_str()) {
                Some(1) => {
                    let from = path.iter().position(|p| p == w).unwrap();
                    let mut c = path[from..].to_vec();
                    c.push(w.clone());
                    return Some(c);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(w, g, state, path) {
                        return Some(c);
                    }
                }
            }
        }
        path.pop();
        state.insert(v.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for v in graph.keys() {
        if !state.contains_key(v.as_str())
            && let Some(c) = visit(v, graph, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn the_core_has_no_import_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, file) in sources(&src) {
        let top = module.split("::").next().unwrap().to_string();
        if top == "lib" || module.ends_with("tests") {
            continue;
        }
        let deps = graph.entry(top.clone()).or_default();
        for path in imports(&file) {
            if let Some(first) = path.first().filter(|f| **f != top) {
                deps.insert(first.clone());
            }
        }
    }
    assert!(graph.len() > 10, "{} modules read", graph.len());
    assert_eq!(
        circle(&graph),
        None,
        "an import circle between core modules"
    );
}

#[test]
fn no_study_of_the_simulator_imports_another_and_no_floor_imports_a_study() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("host-sim/src");
    let mut studies = 0;
    for (module, file) in sources(&src) {
        // The binary's files (main.rs, args.rs, cmd/) call the studies; they are not floors.
        if ["main", "args"].contains(&module.as_str()) || module.starts_with("cmd") {
            continue;
        }
        let own = module.strip_prefix("study::");
        studies += usize::from(own.is_some());
        for path in imports(&file) {
            if path.first().is_some_and(|f| f == "study") {
                let other = path.get(1).map(String::as_str);
                assert!(
                    own.is_some() && other == own,
                    "{module} imports crate::{}",
                    path.join("::")
                );
            }
        }
    }
    assert!(studies >= 9, "{studies} studies read");
}

/// The search finds a circle where there is one (so the two tests above can fail).
#[test]
fn a_circle_is_found() {
    let g = |edges: &[(&str, &str)]| {
        let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (a, b) in edges {
            g.entry(a.to_string()).or_default().insert(b.to_string());
        }
        g
    };
    assert_eq!(circle(&g(&[("a", "b"), ("b", "c")])), None);
    assert!(circle(&g(&[("a", "b"), ("b", "c"), ("c", "a")])).is_some());
}
