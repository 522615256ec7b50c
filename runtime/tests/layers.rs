//! The runtime's layers: no two of its modules import each other (issue
//! 25). A module is a file of `runtime/src/` (`run/integration.rs` is
//! `run::integration`, a `mod.rs` its folder); it imports another when its
//! code (not its comments, not its unit tests) names a path into it,
//! `crate::…` or `super::…`. Re-exports at the crate's root
//! (`pub use run::{integration, solution}`) are followed to the module.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Every module of the runtime by its path (`run::integration`), with its
/// source.
fn modules() -> BTreeMap<String, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = BTreeMap::new();
    let mut folders = vec![root.clone()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(&root).unwrap().with_extension("");
            let mut parts: Vec<String> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
                parts.pop();
            }
            let source = std::fs::read_to_string(&path).unwrap();
            found.insert(parts.join("::"), source);
        }
    }
    found
}

/// The code a module's imports are read from: no comments, no unit tests
/// (by the house's convention the file's last item, after `#[cfg(test)]`).
fn code(source: &str) -> String {
    let source = source.split("#[cfg(test)]").next().unwrap();
    source
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths a module's code names, each a list of segments from the
/// crate's root (`super::` resolved against `module`).
fn paths(module: &str, code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let parent: Vec<&str> = module.split("::").filter(|s| !s.is_empty()).collect();
    let parent = &parent[..parent.len().saturating_sub(1)];
    for (prefix, base) in [("crate::", Vec::new()), ("super::", parent.to_vec())] {
        let mut rest = code;
        while let Some(at) = rest.find(prefix) {
            let before = rest[..at].chars().last();
            rest = &rest[at + prefix.len()..];
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            let mut segments: Vec<String> = base.iter().map(|s| s.to_string()).collect();
            let mut tail = rest;
            loop {
                let end = tail
                    .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .unwrap_or(tail.len());
                if end == 0 {
                    break;
                }
                segments.push(tail[..end].to_string());
                if !tail[end..].starts_with("::") {
                    break;
                }
                tail = &tail[end + 2..];
            }
            // `crate::x::{a, b}`: each of the group.
            if tail.starts_with('{')
                || tail[tail.find(|c: char| c != ':').unwrap_or(0)..].starts_with('{')
            {
                let open = tail.find('{').unwrap();
                let close = tail[open..].find('}').map_or(tail.len(), |c| open + c);
                for item in tail[open + 1..close].split(',') {
                    let mut grouped = segments.clone();
                    grouped.extend(
                        item.trim()
                            .split("::")
                            .map(|s| s.trim().to_string())
                            .filter(|s| !s.is_empty()),
                    );
                    out.push(grouped);
                }
            }
            out.push(segments);
        }
    }
    out
}

/// The module a path leads into: its longest prefix that is a module,
/// after the crate root's re-exports of modules.
fn target(path: &[String], modules: &BTreeMap<String, String>) -> Option<String> {
    let aliases = aliases(modules);
    let mut path = path.to_vec();
    if let Some(first) = path.first() {
        if let Some((_, to)) = aliases.iter().find(|(from, _)| first == from) {
            let mut resolved: Vec<String> = to.split("::").map(String::from).collect();
            resolved.extend(path.drain(1..));
            path = resolved;
        }
    }
    (1..=path.len())
        .rev()
        .map(|k| path[..k].join("::"))
        .find(|candidate| modules.contains_key(candidate))
}

/// The crate root's re-exports of modules under their old flat names
/// (`pub use ode::{dop853, …}` makes `crate::dop853` name `ode::dop853`):
/// `(name, module)`.
fn aliases(modules: &BTreeMap<String, String>) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let root = modules.get("").map_or(String::new(), |s| code(s));
    for line in root.split(';') {
        let Some(rest) = line.trim().strip_prefix("pub use ") else {
            continue;
        };
        let (base, names) = match rest.split_once("::{") {
            Some((base, group)) => (base, group.trim_end_matches('}').to_string()),
            None => match rest.rsplit_once("::") {
                Some((base, name)) => (base, name.to_string()),
                None => continue,
            },
        };
        for name in names.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            let module = format!("{base}::{name}");
            if modules.contains_key(&module) {
                out.push((name.to_string(), module));
            }
        }
    }
    out
}

fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let modules = modules();
    let mut graph = BTreeMap::new();
    for (module, source) in &modules {
        let code = code(source);
        let targets: BTreeSet<String> = paths(module, &code)
            .iter()
            .filter_map(|p| target(p, &modules))
            .filter(|t| t != module && !t.is_empty())
            .collect();
        graph.insert(module.clone(), targets);
    }
    graph
}

#[test]
fn no_two_runtime_modules_import_each_other() {
    let graph = imports();
    let mut both_ways = Vec::new();
    for (a, targets) in &graph {
        for b in targets {
            if a < b && graph.get(b).is_some_and(|t| t.contains(a)) {
                both_ways.push(format!("{a} <-> {b}"));
            }
        }
    }
    assert!(
        both_ways.is_empty(),
        "modules that import each other: {both_ways:?}"
    );
    // The reader sees what it should: the run imports the integrators'
    // interface, never the other way.
    assert!(graph["run::integration"].contains("method::solver"));
    assert!(!graph["method::solver"].iter().any(|t| t.starts_with("run")));
}

#[test]
fn the_checker_sees_an_import_both_ways() {
    // Two made-up modules naming each other, one through a group and
    // `super::`: the checker must find both edges.
    let mut modules = BTreeMap::new();
    modules.insert("a::x".to_string(), String::new());
    modules.insert("a::y".to_string(), String::new());
    let from_x = paths("a::x", &code("use super::y::{Thing, other};\n"));
    let from_y = paths(
        "a::y",
        &code("// crate::b is a comment\nfn f() { crate::a::x::g() }\n"),
    );
    assert!(from_x
        .iter()
        .any(|p| target(p, &modules).as_deref() == Some("a::y")));
    assert!(from_y
        .iter()
        .any(|p| target(p, &modules).as_deref() == Some("a::x")));
    assert_eq!(
        paths("a::y", &code("// crate::a::x\n")),
        Vec::<Vec<String>>::new()
    );
}

/// The runtime's layers, bottom up: the model and its plain values at the
/// root; the one-step integrators (`ode/`); the methods over them
/// (`method/`); the run (`run/`); the edge (`io/`). A module imports only
/// its own layer and those below.
const LAYERS: [&str; 5] = ["", "ode", "method", "run", "io"];

fn layer(module: &str) -> usize {
    let top = module.split("::").next().unwrap_or("");
    LAYERS.iter().position(|l| *l == top).unwrap_or(0)
}

/// Edges from a module to a module of a higher layer (the crate's root,
/// whose re-exports only keep the old names, excepted).
fn upward(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<String> {
    let mut out = Vec::new();
    for (a, targets) in graph {
        if a.is_empty() {
            continue;
        }
        for b in targets {
            if layer(b) > layer(a) {
                out.push(format!("{a} -> {b}"));
            }
        }
    }
    out
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let graph = imports();
    let up = upward(&graph);
    assert!(up.is_empty(), "imports into a higher layer: {up:?}");
    // Every layer is there, and the reader sees the expected edges.
    assert!(graph["method::direct"].contains("ode::stepper"));
    assert!(graph["run::integration"].contains("method::solver"));
    assert!(graph["io::cli::run"].iter().any(|t| t.starts_with("run")));
}

#[test]
fn the_runtime_names_its_modules_by_their_folders() {
    // The crate root re-exports the old flat names (`crate::dop853`) for
    // the generated crates, the Python module and the FMU; the runtime's
    // own code names each module where it lives (`crate::ode::dop853`).
    let modules = modules();
    let aliases = aliases(&modules);
    let mut flat = Vec::new();
    for (module, source) in &modules {
        if module.is_empty() {
            continue;
        }
        for path in paths(module, &code(source)) {
            let from_crate = source_names_crate_path(source, &path);
            if from_crate && aliases.iter().any(|(name, _)| path.first() == Some(name)) {
                flat.push(format!("{module}: crate::{}", path.join("::")));
            }
        }
    }
    flat.sort();
    flat.dedup();
    assert!(
        flat.is_empty(),
        "modules named by their old flat names: {flat:?}"
    );
}

/// Whether `path` (from the root) is written `crate::…` in `source` (not
/// reached through `super::`).
fn source_names_crate_path(source: &str, path: &[String]) -> bool {
    path.first()
        .is_some_and(|first| code(source).contains(&format!("crate::{first}")))
}

#[test]
fn the_layer_check_sees_an_import_upward() {
    let mut graph = BTreeMap::new();
    graph.insert(
        "ode::stepper".to_string(),
        BTreeSet::from(["run::options".to_string()]),
    );
    graph.insert("run::options".to_string(), BTreeSet::new());
    assert_eq!(upward(&graph), vec!["ode::stepper -> run::options"]);
    graph.insert(
        "ode::stepper".to_string(),
        BTreeSet::from(["model".to_string(), "ode::system".to_string()]),
    );
    assert!(upward(&graph).is_empty());
}
