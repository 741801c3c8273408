//! The maps of what runs name only what runs: every function that the text blocks of
//! `collide/mod.rs`'s module doc name (`name()`, `Type::name()`, `module::name()`), and those
//! of the collisions paragraph of docs/architecture.md, is defined in `crates/kinema/src`
//! outside the tests and called there outside its definition and outside the tests (files
//! under `tests/` folders, `oracles.rs`, and every item or module under `#[cfg(test)]` are
//! test code; comments and string literals are not code).
//!
//! The checks are textual, not a compiler's: a method counts as called when some `.name(`
//! is, whatever its receiver. They catch a map that names a function the step no longer has
//! or that only the tests call, which is how maps go stale.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn crate_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// `code` with its comments and the contents of its string and character literals replaced
/// by spaces, line breaks kept (so that line numbers still match).
fn blank(code: &str) -> String {
    let c: Vec<char> = code.chars().collect();
    let mut out = String::with_capacity(code.len());
    let keep = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                keep(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    keep(&mut out, c[i]);
                    keep(&mut out, c[i + 1]);
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    keep(&mut out, c[i]);
                    keep(&mut out, c[i + 1]);
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    keep(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if c[i] == 'r' && (i == 0 || !is_ident(c[i - 1])) && matches!(next, Some('"') | Some('#')) {
            // a raw string r"…" or r#"…"# (or the identifier r#name, which has no quote)
            let mut hashes = 0;
            while c.get(i + 1 + hashes) == Some(&'#') {
                hashes += 1;
            }
            if c.get(i + 1 + hashes) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            let start = i;
            i += 2 + hashes;
            while i < c.len() && !(c[i] == '"' && (0..hashes).all(|h| c.get(i + 1 + h) == Some(&'#'))) {
                i += 1;
            }
            i = (i + 1 + hashes).min(c.len());
            c[start..i].iter().for_each(|&ch| keep(&mut out, ch));
        } else if c[i] == '"' {
            keep(&mut out, c[i]);
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    keep(&mut out, c[i]);
                    i += 1;
                }
                if i < c.len() {
                    keep(&mut out, c[i]);
                    i += 1;
                }
            }
            if i < c.len() {
                keep(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '\'' && (next == Some('\\') || c.get(i + 2) == Some(&'\'')) {
            // a character literal ('x', '\n', '\u{…}'); a lifetime ('a) has no closing quote
            keep(&mut out, c[i]);
            i += 1;
            if c[i] == '\\' {
                keep(&mut out, c[i]);
                i += 1;
            }
            while i < c.len() && c[i] != '\'' {
                keep(&mut out, c[i]);
                i += 1;
            }
            if i < c.len() {
                keep(&mut out, c[i]);
                i += 1;
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The engine's code outside the tests: each file of `crates/kinema/src` that is not test
/// code, with its lines (blanked by [`blank`]) that are not under `#[cfg(test)]`.
struct Engine {
    files: Vec<(PathBuf, Vec<String>)>,
}

impl Engine {
    fn read() -> Engine {
        let src = crate_root().join("src");
        let mut all = Vec::new();
        let mut stack = vec![src.clone()];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    all.push(path);
                }
            }
        }
        all.sort();
        // Files that are test code: under a `tests` folder, the oracles, and every module
        // file declared under `#[cfg(test)]`.
        let mut test_files: BTreeSet<PathBuf> = all
            .iter()
            .filter(|p| p.strip_prefix(&src).unwrap().components().any(|c| c.as_os_str() == "tests"))
            .cloned()
            .collect();
        test_files.insert(src.join("collide/oracles.rs"));
        let mut kept = Vec::new();
        for path in &all {
            let raw = std::fs::read_to_string(path).unwrap();
            let (lines, declared) = strip_test_items(path, &raw);
            test_files.extend(declared);
            kept.push((path.clone(), lines));
        }
        let files = kept.into_iter().filter(|(p, _)| !test_files.contains(p)).collect();
        Engine { files }
    }

    /// Every (file, line number, line) of the engine's code.
    fn lines(&self) -> impl Iterator<Item = (&Path, usize, &str)> {
        self.files
            .iter()
            .flat_map(|(p, lines)| lines.iter().enumerate().map(move |(k, l)| (p.as_path(), k, l.as_str())))
    }
}

/// The lines of the file at `path` (text `raw`), blanked, with every item under
/// `#[cfg(test)]` blanked too; and the module files declared under `#[cfg(test)]`
/// (`#[cfg(test)] mod name;`, with or without `#[path = "…"]`), which are test code.
fn strip_test_items(path: &Path, raw: &str) -> (Vec<String>, Vec<PathBuf>) {
    let raw_lines: Vec<&str> = raw.lines().collect();
    let mut lines: Vec<String> = blank(raw).lines().map(str::to_string).collect();
    let mut declared = Vec::new();
    let dir = path.parent().unwrap();
    let stem = path.file_stem().unwrap().to_str().unwrap();
    let mod_rs = stem == "mod" || stem == "lib" || stem == "main";
    let mut k = 0;
    while k < lines.len() {
        if lines[k].trim() != "#[cfg(test)]" {
            k += 1;
            continue;
        }
        // the item: after its attributes
        let mut item = k + 1;
        let mut path_attr = None;
        while item < lines.len() && (lines[item].trim_start().starts_with("#[") || lines[item].trim().is_empty()) {
            if let Some(p) = raw_lines[item].trim().strip_prefix("#[path = \"") {
                path_attr = p.strip_suffix("\"]").map(str::to_string);
            }
            item += 1;
        }
        let head = lines.get(item).map_or("", |l| l.trim());
        let words: Vec<&str> = head.split(|c: char| !is_ident(c)).filter(|w| !w.is_empty()).collect();
        if let (Some(at), true) = (words.iter().position(|w| *w == "mod"), head.ends_with(';')) {
            let name = words[at + 1];
            declared.push(match path_attr {
                Some(p) => dir.join(p),
                None if mod_rs => dir.join(format!("{name}.rs")),
                None => dir.join(stem).join(format!("{name}.rs")),
            });
            declared.push(dir.join(name).join("mod.rs"));
        }
        // blank from the attribute to the item's end: its `;` before any brace, or the
        // brace that closes its first one
        let mut depth = 0i64;
        let mut opened = false;
        let mut end = item;
        'item: for (m, line) in lines.iter().enumerate().skip(item) {
            for ch in line.chars() {
                match ch {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    ';' if !opened => {
                        end = m;
                        break 'item;
                    }
                    _ => {}
                }
                if opened && depth == 0 {
                    end = m;
                    break 'item;
                }
            }
            end = m;
        }
        let last = end.min(lines.len() - 1);
        for line in &mut lines[k..=last] {
            line.clear();
        }
        k = end + 1;
    }
    (lines, declared)
}

/// The starts of `word` in `line` as a whole identifier.
fn word_at(line: &str, word: &str) -> Vec<usize> {
    let b = line.as_bytes();
    line.match_indices(word)
        .map(|(at, _)| at)
        .filter(|&at| {
            let before = at == 0 || !is_ident(b[at - 1] as char);
            let after = b.get(at + word.len()).is_none_or(|&c| !is_ident(c as char));
            before && after
        })
        .collect()
}

/// What a map names: `name`, `Type::name` or `module::name` (the last two segments of a path).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Named {
    qualifier: Option<String>,
    name: String,
}

impl std::fmt::Display for Named {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.qualifier {
            Some(q) => write!(f, "{q}::{}", self.name),
            None => write!(f, "{}", self.name),
        }
    }
}

/// The functions a map's text names: each path followed by `(` (`name(`, `Type::name(`,
/// `module::name(`), and each path with `::` whose last segment is lower case.
fn named_in(text: &str) -> BTreeSet<Named> {
    let c: Vec<char> = text.chars().collect();
    let mut found = BTreeSet::new();
    let mut i = 0;
    while i < c.len() {
        let starts = (c[i].is_ascii_alphabetic() || c[i] == '_') && (i == 0 || !(is_ident(c[i - 1]) || c[i - 1] == ':'));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        let mut segments = vec![String::new()];
        while j < c.len() {
            if is_ident(c[j]) {
                segments.last_mut().unwrap().push(c[j]);
                j += 1;
            } else if c[j] == ':' && c.get(j + 1) == Some(&':') && c.get(j + 2).is_some_and(|&n| is_ident(n)) {
                segments.push(String::new());
                j += 2;
            } else {
                break;
            }
        }
        let last = segments.last().unwrap().clone();
        let called = c.get(j) == Some(&'(');
        let pathed = segments.len() > 1 && last.starts_with(|ch: char| ch.is_ascii_lowercase() || ch == '_');
        if called || pathed {
            found.insert(Named {
                qualifier: (segments.len() > 1).then(|| segments[segments.len() - 2].clone()),
                name: last,
            });
        }
        i = j;
    }
    found
}

/// Why `named` is not a function the engine defines and calls outside the tests, if it is not.
fn check(engine: &Engine, named: &Named) -> Option<String> {
    let name = named.name.as_str();
    let type_like = named
        .qualifier
        .as_ref()
        .filter(|q| q.starts_with(|c: char| c.is_ascii_uppercase()));
    let module = named
        .qualifier
        .as_ref()
        .filter(|q| q.starts_with(|c: char| c.is_ascii_lowercase()));
    // (a) defined: `fn name`, in an impl of the type, or at the top of the module's file
    let mut defined = false;
    let mut definitions = BTreeSet::new();
    for (file, lines) in &engine.files {
        for (k, line) in lines.iter().enumerate() {
            let is_def = word_at(line, name).iter().any(|&at| line[..at].trim_end().ends_with("fn"));
            if !is_def {
                continue;
            }
            definitions.insert((file.clone(), k));
            let fits = if let Some(t) = type_like {
                // the nearest enclosing top-level item above the definition is `impl … Type`
                lines[..k]
                    .iter()
                    .rev()
                    .find(|l| l.starts_with("impl") || l.trim_end() == "}")
                    .is_some_and(|l| l.starts_with("impl") && !word_at(l, t).is_empty())
            } else if let Some(m) = module {
                let stem = file.file_stem().unwrap().to_str().unwrap();
                let parent = file.parent().and_then(|p| p.file_name()).and_then(|n| n.to_str());
                let in_module = stem == m.as_str() || (stem == "mod" && parent == Some(m.as_str()));
                in_module && !line.starts_with(char::is_whitespace)
            } else {
                true
            };
            defined |= fits;
        }
    }
    if !defined {
        return Some(format!(
            "{named}: no `fn {name}` of that name in crates/kinema/src outside the tests"
        ));
    }
    // (b) called: `name(` or `name::<…>(`, as `.name(` for a method, outside the tests and
    // not at a definition
    let called = engine.lines().any(|(file, k, line)| {
        if definitions.contains(&(file.to_path_buf(), k)) {
            return false;
        }
        word_at(line, name).into_iter().any(|at| {
            let after = line[at + name.len()..].trim_start();
            let call = after.starts_with('(') || (after.starts_with("::<") && after.contains(">("));
            let before = line[..at].trim_end();
            let how = if let Some(t) = type_like {
                before.ends_with('.') || before.ends_with(&format!("{t}::")) || before.ends_with("Self::")
            } else if let Some(m) = module {
                !before.ends_with('.') && (!before.ends_with("::") || before.ends_with(&format!("{m}::")))
            } else {
                true
            };
            call && how && !before.ends_with("fn")
        })
    });
    if !called {
        return Some(format!(
            "{named}: defined, but nothing in crates/kinema/src calls it outside the tests"
        ));
    }
    None
}

/// The text blocks (```text … ```) of `collide/mod.rs`'s module doc: the maps.
fn maps_of_collide() -> String {
    let doc = std::fs::read_to_string(crate_root().join("src/collide/mod.rs")).unwrap();
    let mut maps = String::new();
    let mut inside = false;
    for line in doc.lines().map_while(|l| l.strip_prefix("//!")) {
        let line = line.strip_prefix(' ').unwrap_or(line);
        if line.trim() == "```text" {
            inside = true;
        } else if line.trim() == "```" {
            inside = false;
        } else if inside {
            maps.push_str(line);
            maps.push('\n');
        }
    }
    maps
}

/// The text block that follows docs/architecture.md's paragraph on the collisions
/// (`**Collisions**`).
fn map_of_architecture() -> String {
    let doc = std::fs::read_to_string(crate_root().join("../../docs/architecture.md")).unwrap();
    let mut lines = doc.lines().skip_while(|l| !l.starts_with("**Collisions**"));
    let block: Vec<&str> = lines
        .by_ref()
        .skip_while(|l| l.trim() != "```text")
        .skip(1)
        .take_while(|l| l.trim() != "```")
        .collect();
    block.join("\n")
}

/// The reasons each of `map`'s names fails [`check`], and how many it names.
fn problems(engine: &Engine, map: &str) -> (Vec<String>, usize) {
    let named = named_in(map);
    (named.iter().filter_map(|n| check(engine, n)).collect(), named.len())
}

#[test]
fn the_map_of_collide_names_only_functions_a_step_calls() {
    let engine = Engine::read();
    let map = maps_of_collide();
    let (bad, count) = problems(&engine, &map);
    assert!(count >= 30, "the map names {count} functions: {:?}", named_in(&map));
    assert!(
        bad.is_empty(),
        "collide/mod.rs's map names what no step calls:\n{}",
        bad.join("\n")
    );
    // and each file it names exists (under collide/, or under src/ for world/…)
    let src = crate_root().join("src");
    for token in map.split(|c: char| c.is_whitespace() || "(),:;→".contains(c)) {
        if token.ends_with(".rs") {
            assert!(
                src.join("collide").join(token).is_file() || src.join(token).is_file(),
                "collide/mod.rs's map names {token}, which is not a file"
            );
        }
    }
}

#[test]
fn the_map_of_the_architecture_names_only_functions_a_step_calls() {
    let engine = Engine::read();
    let map = map_of_architecture();
    let (bad, count) = problems(&engine, &map);
    assert!(
        count >= 10,
        "docs/architecture.md's collisions map names {count} functions:\n{map}"
    );
    assert!(
        bad.is_empty(),
        "docs/architecture.md's collisions map names what no step calls:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_map_check_fails_on_what_is_gone_or_runs_only_in_tests() {
    // a function that is gone, one only the tests define, one only the tests call, a method
    // of the wrong type, and a module's function that lives elsewhere
    let engine = Engine::read();
    let (bad, count) = problems(
        &engine,
        "positions ──Grid::find_pairs()──▶ all_pairs(), Grid::cells(), Grid::end_contacts(), islands::settle()",
    );
    assert_eq!(count, 5);
    assert_eq!(bad.len(), 5, "{bad:#?}");
    // and the checker reads past comments, strings and test modules
    let code = "let s = \"fn fake(\"; // fake()\nlet c = '\"'; /* fake( */ real();\n";
    let blanked = blank(code);
    assert_eq!(blanked.lines().count(), 2);
    assert!(!blanked.contains("fake") && blanked.contains("real();"), "{blanked}");
}

/// The body of `named`'s definition (the lines from its `fn` to the brace that closes it),
/// found as [`check`] finds definitions; `None` if there is no such definition.
fn body_of(engine: &Engine, named: &Named) -> Option<Vec<String>> {
    let name = named.name.as_str();
    let qualifier = named.qualifier.as_deref();
    for (file, lines) in &engine.files {
        for (k, line) in lines.iter().enumerate() {
            if !word_at(line, name).iter().any(|&at| line[..at].trim_end().ends_with("fn")) {
                continue;
            }
            let fits = match qualifier {
                Some(t) if t.starts_with(|c: char| c.is_ascii_uppercase()) => lines[..k]
                    .iter()
                    .rev()
                    .find(|l| l.starts_with("impl") || l.trim_end() == "}")
                    .is_some_and(|l| l.starts_with("impl") && !word_at(l, t).is_empty()),
                Some(m) => {
                    let stem = file.file_stem().unwrap().to_str().unwrap();
                    (stem == m
                        || (stem == "mod" && file.parent().and_then(|p| p.file_name()).and_then(|n| n.to_str()) == Some(m)))
                        && !line.starts_with(char::is_whitespace)
                }
                None => true,
            };
            if !fits {
                continue;
            }
            let mut depth = 0i64;
            for (m, l) in lines.iter().enumerate().skip(k) {
                depth += l.matches('{').count() as i64 - l.matches('}').count() as i64;
                if depth == 0 && l.contains('}') {
                    return Some(lines[k..=m].to_vec());
                }
            }
        }
    }
    None
}

/// Whether `body` calls `callee` (`name(`, `name::<…>(`, as `.name(`, `Type::name(` or
/// `module::name(` when it is qualified).
fn calls(body: &[String], callee: &Named) -> bool {
    let name = callee.name.as_str();
    body.iter().skip(1).any(|line| {
        word_at(line, name).into_iter().any(|at| {
            let after = line[at + name.len()..].trim_start();
            let before = line[..at].trim_end();
            let call = after.starts_with('(') || after.starts_with("::<");
            let how = match callee.qualifier.as_deref() {
                Some(q) => before.ends_with('.') || before.ends_with(&format!("{q}::")) || before.ends_with("Self::"),
                None => !before.ends_with('.'),
            };
            call && how
        })
    })
}

/// The links of `chain` (names as the maps write them, caller first) that the engine's code
/// does not make: each name must call the next, or hand the function it calls a closure that
/// does (the caller's caller calls it: `soft_step` hands `passes` the visit).
fn broken_links(engine: &Engine, chain: &[&str]) -> Vec<String> {
    let named: Vec<Named> = chain
        .iter()
        .map(|c| named_in(&format!("{c}()")).into_iter().next().expect("a name"))
        .collect();
    let mut broken = Vec::new();
    for k in 1..named.len() {
        let Some(body) = body_of(engine, &named[k - 1]) else {
            broken.push(format!("{}: no definition", named[k - 1]));
            continue;
        };
        let through_closure = k >= 2 && body_of(engine, &named[k - 2]).is_some_and(|b| calls(&b, &named[k]));
        if !calls(&body, &named[k]) && !through_closure {
            broken.push(format!("{} does not call {}", named[k - 1], named[k]));
        }
    }
    broken
}

/// The deepest call of a step as `collide/mod.rs`'s doc states it: the names in backticks
/// after "calls below `World::step_once`:", up to the next full stop.
fn deepest_call() -> Vec<String> {
    let doc = std::fs::read_to_string(crate_root().join("src/collide/mod.rs")).unwrap();
    let text: String = doc.lines().map_while(|l| l.strip_prefix("//!")).collect::<Vec<_>>().join(" ");
    let from = text
        .find("calls below `World::step_once`:")
        .expect("the doc states the deepest call");
    let rest = &text[from + "calls below `World::step_once`:".len()..];
    let sentence = &rest[..rest.find(" (").unwrap_or(rest.len())];
    sentence.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

#[test]
fn the_deepest_call_of_a_step_is_at_most_eight_calls_below_step_once() {
    // The issue's bound on reading one step: from `World::step_once` to the impulse of one
    // contact in the solve, at most 8 calls. The chain is the doc's, and every link of it is
    // checked against the code: a new layer makes the chain the doc states false.
    let engine = Engine::read();
    let chain = deepest_call();
    assert!(chain.len() <= 8, "{} calls below World::step_once: {chain:?}", chain.len());
    assert_eq!(chain.last().map(String::as_str), Some("Row::visit"), "{chain:?}");
    let mut full = vec!["World::step_once"];
    full.extend(chain.iter().map(|c| c.trim_end_matches("()")));
    // the doc writes the world's methods and the model's by their bare names where clear
    let full: Vec<String> = full
        .iter()
        .map(|c| match *c {
            "collide" => "World::collide".to_string(),
            "solve" => "ImpulseModel::solve".to_string(),
            other => other.to_string(),
        })
        .collect();
    let full: Vec<&str> = full.iter().map(String::as_str).collect();
    let broken = broken_links(&engine, &full);
    assert!(
        broken.is_empty(),
        "the deepest call the doc states is not the code's: {broken:?}"
    );
    // and the check fails on a chain with a link the code does not make
    let wrong = broken_links(&engine, &["World::step_once", "World::collide", "soft_step", "Row::visit"]);
    assert_eq!(wrong, vec!["World::collide does not call soft_step".to_string()]);
}
