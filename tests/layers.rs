//! The layers of the workspace (issue 23): no circle among the modules of a crate, and in the
//! facade and in saddle-core every arrow points to the module's own layer or a lower one.
//!
//! The check reads the source files (`src/` and `crates/*/src/`), one module per file, and
//! takes an arrow A → B wherever A's code names B: a `use` of `crate::…`, `super::…`,
//! `self::…`, a child module or a module imported under a name, and the same paths written in
//! code. Comments and string literals are left out. A `pub use` of a module's own descendants
//! is a door, not an arrow: a path through it is followed to the module that defines the item.
//! A circle is looked for at every depth of the module tree (files, then the folders they are
//! in). The import graph is printed (`cargo test --release --test layers -- --nocapture`).
//! Unit-test modules (`#[cfg(test)] mod tests`) are the module's own tests and left out: a
//! plugin's test may run its crate's kit while the kit's test runs the plugins.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A module's path in its crate (`["studies", "report", "runs"]`; `[]` is the crate root).
type Module = Vec<String>;
/// Module → the modules its code names.
type Graph = BTreeMap<Module, BTreeSet<Module>>;

/// The facade's layers, lowest first: files, then commands, then measurements, then the binary.
const FACADE_LAYERS: [&str; 4] = ["io", "app", "studies", "main"];

/// saddle-core's layers, lowest first: the modules in the order of the table in the crate's doc
/// (`crates/core/src/lib.rs`, "each layer using only those above it in this list").
fn core_layers(lib_rs: &str) -> Vec<String> {
    lib_rs
        .lines()
        .filter_map(|l| l.strip_prefix("//! | [`"))
        .filter_map(|l| l.split_once("`]").map(|(m, _)| m.to_string()))
        .collect()
}

/// One source file: its module, its text, and what `crate::` and an extern crate name mean in
/// it (`main.rs` is its own crate naming the library `saddle::`).
struct SourceFile {
    module: Module,
    text: String,
    /// The module `crate::` starts from.
    crate_base: Module,
    /// An extern crate name that means the library's root (`saddle` in `main.rs`).
    library: Option<&'static str>,
}

// ---------------------------------------------------------------------------------------------
// Reading the files

/// The files of the crate whose sources are in `src`; `library` is the crate's own name as its
/// binary `main.rs` writes it.
fn read_crate(src: &Path, library: &'static str) -> Vec<SourceFile> {
    let mut paths = vec![];
    collect_rs(src, &mut paths);
    paths.sort();
    paths
        .into_iter()
        .map(|path| {
            let rel = path.strip_prefix(src).unwrap();
            let mut module: Module = rel.with_extension("").iter().map(|s| s.to_string_lossy().into_owned()).collect();
            let is_main = module == ["main"];
            if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
                module.pop();
            }
            SourceFile {
                text: std::fs::read_to_string(&path).unwrap(),
                crate_base: if is_main { module.clone() } else { vec![] },
                library: is_main.then_some(library),
                module,
            }
        })
        .collect()
}

fn collect_rs(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect_rs(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tokens

/// The code of `src` without comments, string and character literals (each replaced by a
/// space, so that tokens stay apart).
fn strip(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < c.len() {
        let prev_ident = i > 0 && ident(c[i - 1]);
        if c[i] == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            loop {
                if at(i) == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if at(i) == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else if i >= c.len() {
                    break;
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if !prev_ident && (c[i] == 'r' || (c[i] == 'b' && at(i + 1) == 'r')) && raw_string_at(&c, i).is_some() {
            i = raw_string_at(&c, i).unwrap();
            out.push(' ');
        } else if c[i] == '"' || (!prev_ident && c[i] == 'b' && at(i + 1) == '"') {
            i += if c[i] == 'b' { 2 } else { 1 };
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push(' ');
        } else if c[i] == '\'' && at(i + 1) == '\\' {
            // an escaped character literal: '\n', '\'', '\u{..}'
            i += 3;
            while i < c.len() && c[i] != '\'' {
                i += 1;
            }
            i += 1;
            out.push(' ');
        } else if c[i] == '\'' && at(i + 2) == '\'' {
            i += 3;
            out.push(' ');
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The index after the raw string literal (`r"…"`, `r#"…"#`, `br"…"`) starting at `i`, if one
/// does (`r#type` is a raw identifier, not a string).
fn raw_string_at(c: &[char], mut i: usize) -> Option<usize> {
    if c[i] == 'b' {
        i += 1;
    }
    i += 1;
    let mut hashes = 0;
    while c.get(i) == Some(&'#') {
        hashes += 1;
        i += 1;
    }
    if c.get(i) != Some(&'"') {
        return None;
    }
    i += 1;
    while i < c.len() {
        if c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#')) {
            return Some(i + 1 + hashes);
        }
        i += 1;
    }
    Some(c.len())
}

#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    /// `::`
    Path,
    Punct(char),
}

fn tokens(code: &str) -> Vec<Token> {
    let c: Vec<char> = code.chars().collect();
    let mut out = vec![];
    let mut i = 0;
    while i < c.len() {
        if c[i].is_alphabetic() || c[i] == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            if c[start..i] == ['r'] && c.get(i) == Some(&'#') {
                // a raw identifier r#name is the name
                continue;
            }
            out.push(Token::Ident(c[start..i].iter().collect()));
        } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
            out.push(Token::Path);
            i += 2;
        } else if c[i] == '\'' {
            // a lifetime: skip its name
            i += 1;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
        } else {
            if !c[i].is_whitespace() {
                out.push(Token::Punct(c[i]));
            }
            i += 1;
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Paths named by a file

/// A path a file names: its segments, the module scope it is written in (the file's module,
/// with an inline `mod tests` appended), and how it is named.
#[derive(Clone, Debug)]
struct Named {
    segments: Vec<String>,
    scope: Module,
    kind: Kind,
}

#[derive(Clone, Debug, PartialEq)]
enum Kind {
    /// In code or a private `use`.
    Use,
    /// In a `pub use` (any visibility): a re-export.
    ReExport,
}

/// Every path of `file` that starts with a name (`crate`, `super`, `self`, an identifier
/// followed by `::`), with the scope it is written in; `use` trees are expanded.
fn named_paths(file: &SourceFile) -> Vec<Named> {
    let t = tokens(&strip(&file.text));
    let mut out = vec![];
    let mut scope = file.module.clone();
    // inline modules: (depth of their opening brace)
    let mut inline: Vec<usize> = vec![];
    let mut depth = 0usize;
    let mut i = 0;
    while i < t.len() {
        match &t[i] {
            Token::Punct('{') => depth += 1,
            Token::Punct('}') => {
                depth = depth.saturating_sub(1);
                if inline.last() == Some(&depth) {
                    inline.pop();
                    scope.pop();
                }
            }
            Token::Punct('#') if is_cfg_test(&t, i) => {
                // a unit-test module: skip it whole
                let j = i + 7;
                if let (Some(Token::Ident(m)), Some(Token::Ident(_)), Some(Token::Punct('{'))) =
                    (t.get(j), t.get(j + 1), t.get(j + 2))
                    && m == "mod"
                {
                    i = block_end(&t, j + 3);
                    continue;
                }
            }
            Token::Ident(w) if w == "mod" => {
                if let (Some(Token::Ident(name)), Some(Token::Punct('{'))) = (t.get(i + 1), t.get(i + 2)) {
                    scope.push(name.clone());
                    inline.push(depth);
                    depth += 1;
                    i += 3;
                    continue;
                }
            }
            Token::Ident(w) if w == "use" => {
                let kind = if is_public(&t, i) { Kind::ReExport } else { Kind::Use };
                let mut j = i + 1;
                let mut trees = vec![];
                use_tree(&t, &mut j, vec![], &mut trees);
                out.extend(trees.into_iter().map(|segments| Named {
                    segments,
                    scope: scope.clone(),
                    kind: kind.clone(),
                }));
                i = j;
                continue;
            }
            Token::Punct('#') => {}
            Token::Ident(_) if i == 0 || t[i - 1] != Token::Path => {
                let mut segments = vec![];
                let mut j = i;
                while let Some(Token::Ident(s)) = t.get(j) {
                    segments.push(s.clone());
                    if t.get(j + 1) == Some(&Token::Path) {
                        j += 2;
                    } else {
                        j += 1;
                        break;
                    }
                }
                if segments.len() > 1 {
                    out.push(Named { segments, scope: scope.clone(), kind: Kind::Use });
                    i = j;
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// The index after the block whose opening brace is just before `j`.
fn block_end(t: &[Token], mut j: usize) -> usize {
    let mut depth = 1;
    while depth > 0 && j < t.len() {
        match t[j] {
            Token::Punct('{') => depth += 1,
            Token::Punct('}') => depth -= 1,
            _ => {}
        }
        j += 1;
    }
    j
}

/// True when the tokens at `i` are `#[cfg(test)]`.
fn is_cfg_test(t: &[Token], i: usize) -> bool {
    let want = [
        Token::Punct('#'),
        Token::Punct('['),
        Token::Ident("cfg".into()),
        Token::Punct('('),
        Token::Ident("test".into()),
        Token::Punct(')'),
        Token::Punct(']'),
    ];
    t.get(i..i + want.len()) == Some(&want[..])
}

/// True when the `use` at `i` is preceded by a visibility (`pub`, `pub(crate)`, `pub(super)`).
fn is_public(t: &[Token], i: usize) -> bool {
    match i.checked_sub(1).map(|k| &t[k]) {
        Some(Token::Ident(w)) => w == "pub",
        Some(Token::Punct(')')) => t[..i]
            .iter()
            .rposition(|x| *x == Token::Punct('('))
            .is_some_and(|k| k > 0 && t[k - 1] == Token::Ident("pub".into())),
        _ => false,
    }
}

/// Expands the use tree at `j` (after `use`, or inside braces) into its paths; `self` in a
/// group names the group's module. Leaves `j` after the tree.
fn use_tree(t: &[Token], j: &mut usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    let mut path = prefix;
    loop {
        match t.get(*j) {
            Some(Token::Path) => *j += 1,
            Some(Token::Punct('{')) => {
                *j += 1;
                loop {
                    match t.get(*j) {
                        Some(Token::Punct('}')) => {
                            *j += 1;
                            break;
                        }
                        Some(Token::Punct(',')) => *j += 1,
                        None => return,
                        _ => use_tree(t, j, path.clone(), out),
                    }
                }
                return;
            }
            Some(Token::Punct('*')) => {
                *j += 1;
                out.push(path);
                return;
            }
            Some(Token::Ident(w)) if w == "self" && !path.is_empty() => {
                *j += 1;
                skip_alias(t, j);
                out.push(path);
                return;
            }
            Some(Token::Ident(w)) => {
                path.push(w.clone());
                *j += 1;
                if t.get(*j) != Some(&Token::Path) {
                    skip_alias(t, j);
                    out.push(path);
                    return;
                }
            }
            _ => {
                // `;`, `,` or `}` ends a tree
                if !path.is_empty() {
                    out.push(path);
                }
                if t.get(*j) == Some(&Token::Punct(';')) {
                    *j += 1;
                }
                return;
            }
        }
    }
}

fn skip_alias(t: &[Token], j: &mut usize) {
    if t.get(*j) == Some(&Token::Ident("as".into())) {
        *j += 2;
    }
}

// ---------------------------------------------------------------------------------------------
// The graph

/// A crate's modules and the doors (re-exports) of each: module → name → the path it names
/// (with the scope it is written in).
struct Crate {
    modules: BTreeSet<Module>,
    doors: BTreeMap<Module, BTreeMap<String, Named>>,
}

impl Crate {
    /// The module a path names, written in `scope` of a file whose `crate::` is `crate_base`:
    /// the deepest module on the path, through re-exports; `None` for paths outside the crate
    /// (`std::`, another crate, a local item).
    fn resolve(
        &self,
        named: &Named,
        file: &SourceFile,
        aliases: &BTreeMap<String, Module>,
        hops: usize,
    ) -> Option<Module> {
        self.resolve_in(named, (&file.crate_base, file.library), aliases, hops)
    }

    /// [`Crate::resolve`] with `crate::` meaning `crate_base` and `library` the library's root.
    fn resolve_in(
        &self,
        named: &Named,
        (crate_base, library): (&Module, Option<&str>),
        aliases: &BTreeMap<String, Module>,
        hops: usize,
    ) -> Option<Module> {
        let s = &named.segments;
        let (mut base, rest): (Module, &[String]) = match s[0].as_str() {
            "crate" => (crate_base.clone(), &s[1..]),
            "self" => (named.scope.clone(), &s[1..]),
            "super" => {
                let mut b = named.scope.clone();
                let k = s.iter().take_while(|x| *x == "super").count();
                for _ in 0..k {
                    b.pop();
                }
                (b, &s[k..])
            }
            name if library == Some(name) => (vec![], &s[1..]),
            name if aliases.contains_key(name) => (aliases[name].clone(), &s[1..]),
            name if self.modules.contains(&[named.scope.as_slice(), &[name.to_string()]].concat()) => {
                (named.scope.clone(), &s[..])
            }
            _ => return None,
        };
        for seg in rest {
            let next = [base.as_slice(), std::slice::from_ref(seg)].concat();
            if self.modules.contains(&next) {
                base = next;
                continue;
            }
            if let Some(door) = self.doors.get(&base).and_then(|d| d.get(seg)).filter(|_| hops < 8) {
                // a door is written in a module of the library
                return self.resolve_in(door, (&vec![], None), &BTreeMap::new(), hops + 1).or(Some(base));
            }
            break;
        }
        // an inline module (`mod tests`) belongs to its file
        while !self.modules.contains(&base) && !base.is_empty() {
            base.pop();
        }
        Some(base)
    }
}

/// The import graph of a crate's files: every module with the modules its code names.
fn graph(files: &[SourceFile]) -> Graph {
    let modules: BTreeSet<Module> = files.iter().map(|f| f.module.clone()).collect();
    let named: Vec<Vec<Named>> = files.iter().map(named_paths).collect();
    let mut krate = Crate { modules, doors: BTreeMap::new() };
    // doors: the names a module re-exports
    for (file, paths) in files.iter().zip(&named) {
        for n in paths.iter().filter(|n| n.kind == Kind::ReExport && n.scope == file.module) {
            let name = n.segments.last().unwrap().clone();
            krate.doors.entry(file.module.clone()).or_default().insert(name, n.clone());
        }
    }
    let mut g = Graph::new();
    for (file, paths) in files.iter().zip(&named) {
        let edges = g.entry(file.module.clone()).or_default();
        // modules imported under a name: `use crate::app::run;`, `use super::{self, x}`
        let mut aliases = BTreeMap::new();
        for n in paths.iter().filter(|n| n.kind == Kind::Use && n.segments.len() > 1) {
            if let Some(m) = krate.resolve(n, file, &BTreeMap::new(), 0)
                && m.last() == n.segments.last()
                && krate.modules.contains(&m)
            {
                aliases.insert(n.segments.last().unwrap().clone(), m);
            }
        }
        for n in paths {
            let Some(target) = krate.resolve(n, file, &aliases, 0) else { continue };
            // a module's re-export of its own descendants is a door, not an arrow
            let door = n.kind == Kind::ReExport && target.starts_with(&file.module);
            if target != file.module && !door {
                edges.insert(target);
            }
        }
    }
    g
}

/// The graph with every module cut to its first `depth` segments (its folder at that depth).
fn folded(g: &Graph, depth: usize) -> Graph {
    let cut = |m: &Module| m[..m.len().min(depth)].to_vec();
    let mut out = Graph::new();
    for (a, bs) in g {
        let edges = out.entry(cut(a)).or_default();
        edges.extend(bs.iter().map(cut).filter(|b| *b != cut(a)));
    }
    out
}

/// The circles of `g`: its strongly connected components of more than one module (Tarjan).
fn circles(g: &Graph) -> Vec<Vec<Module>> {
    struct Tarjan<'a> {
        g: &'a Graph,
        index: BTreeMap<&'a Module, usize>,
        low: BTreeMap<&'a Module, usize>,
        stack: Vec<&'a Module>,
        on_stack: BTreeSet<&'a Module>,
        out: Vec<Vec<Module>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, v: &'a Module) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.g.get(v).into_iter().flatten() {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let lw = self.low[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.on_stack.contains(w) {
                    let iw = self.index[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = vec![];
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    component.push(w.clone());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.out.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: vec![],
        on_stack: BTreeSet::new(),
        out: vec![],
    };
    for v in g.keys() {
        if !t.index.contains_key(v) {
            t.visit(v);
        }
    }
    t.out
}

/// The circles at every depth of the module tree, each as `a, b, c (a → b, b → c, c → a)`: its
/// modules and the arrows among them.
fn all_circles(g: &Graph) -> Vec<String> {
    let depth = g.keys().map(Vec::len).max().unwrap_or(0);
    let mut out = BTreeSet::new();
    for d in 1..=depth {
        let f = folded(g, d);
        for c in circles(&f) {
            let arrows: Vec<String> = c
                .iter()
                .flat_map(|a| f[a].iter().filter(|b| c.contains(b)).map(move |b| format!("{} → {}", name(a), name(b))))
                .collect();
            let modules: Vec<String> = c.iter().map(name).collect();
            out.insert(format!("{} ({})", modules.join(", "), arrows.join(", ")));
        }
    }
    out.into_iter().collect()
}

/// The arrows of `g` from a module to a module of a higher layer (`layers` lowest first, by
/// the first segment), and the top-level modules in no layer. The crate root only declares.
fn upward_arrows(g: &Graph, layers: &[&str]) -> Vec<String> {
    let layer = |m: &Module| m.first().map(|top| layers.iter().position(|l| l == top));
    let mut out = vec![];
    let unlayered: BTreeSet<&String> = g.keys().filter(|m| layer(m) == Some(None)).map(|m| &m[0]).collect();
    out.extend(unlayered.iter().map(|top| format!("{top} is in no layer of {layers:?}")));
    for (a, bs) in g {
        for b in bs {
            if let (Some(Some(la)), Some(Some(lb))) = (layer(a), layer(b))
                && lb > la
            {
                out.push(format!("{} → {} points up ({} below {})", name(a), name(b), layers[la], layers[lb]));
            }
        }
    }
    out
}

fn name(m: &Module) -> String {
    if m.is_empty() { "crate".into() } else { m.join("::") }
}

/// The graph as lines `module → a, b, c`.
fn print_graph(title: &str, g: &Graph) {
    println!("{title}");
    for (a, bs) in g {
        let targets: Vec<String> = bs.iter().map(name).collect();
        println!("  {} → {}", name(a), if targets.is_empty() { "(nothing)".to_string() } else { targets.join(", ") });
    }
}

fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

// ---------------------------------------------------------------------------------------------
// The checks

/// The facade: io < app < studies < main, no circle.
#[test]
fn the_facade_is_in_layers_without_circles() {
    let g = graph(&read_crate(&workspace().join("src"), "saddle"));
    print_graph("saddle (the facade; layers io < app < studies < main):", &g);
    let up = upward_arrows(&g, &FACADE_LAYERS);
    assert!(up.is_empty(), "upward arrows in the facade: {up:#?}");
    let circles = all_circles(&g);
    assert!(circles.is_empty(), "circles in the facade: {circles:#?}");
}

/// saddle-core: the layers of its doc table (error < linalg < mesh < problem < fem < evolution
/// when this was written), no circle (inside `problem` neither).
#[test]
fn the_core_is_in_layers_without_circles() {
    let src = workspace().join("crates/core/src");
    let layers = core_layers(&std::fs::read_to_string(src.join("lib.rs")).unwrap());
    assert!(layers.len() >= 6 && layers[0] == "error", "the layer table of saddle-core's doc: {layers:?}");
    let g = graph(&read_crate(&src, "saddle_core"));
    print_graph(&format!("saddle-core (layers {}):", layers.join(" < ")), &g);
    let layers: Vec<&str> = layers.iter().map(String::as_str).collect();
    let up = upward_arrows(&g, &layers);
    assert!(up.is_empty(), "upward arrows in saddle-core: {up:#?}");
    let circles = all_circles(&g);
    assert!(circles.is_empty(), "circles in saddle-core: {circles:#?}");
}

/// The other crates: no circle.
#[test]
fn the_other_crates_have_no_circle() {
    for (dir, library) in [
        ("crates/yield/src", "saddle_yield"),
        ("crates/contact/src", "saddle_contact"),
        ("crates/solvers/src", "saddle_solvers"),
        ("crates/mpi/src", "saddle_mpi"),
        ("crates/parallel/src", "saddle_parallel"),
    ] {
        let g = graph(&read_crate(&workspace().join(dir), library));
        print_graph(&format!("{dir}:"), &g);
        let circles = all_circles(&g);
        assert!(circles.is_empty(), "circles in {dir}: {circles:#?}");
    }
}

// ---------------------------------------------------------------------------------------------
// The check catches what it must

fn file(module: &str, text: &str) -> SourceFile {
    let module: Module = if module.is_empty() { vec![] } else { module.split("::").map(String::from).collect() };
    SourceFile { module, text: text.into(), crate_base: vec![], library: None }
}

fn edges(g: &Graph, from: &str) -> Vec<String> {
    let m: Module = from.split("::").map(String::from).collect();
    g[&m].iter().map(name).collect()
}

/// Paths in `use` trees, `super::`, child modules, imported modules and code are arrows;
/// comments, strings and a parent's re-export of its children are not.
#[test]
fn arrows_are_read_from_uses_and_code_not_comments_or_strings() {
    let files = [
        file("", "pub mod io; pub mod app; pub use app::run::Run;"),
        file("io", "pub mod scene; pub mod summary; pub use summary::Summary;"),
        file(
            "io::scene",
            "/// [`crate::app::run`] in a doc\nconst S: &str = \"crate::app::run\"; const C: char = '{';",
        ),
        file("io::summary", "use super::scene::{self, Scene}; fn f() { scene::g(); }"),
        file("app", "pub mod run; pub mod sweep;"),
        file("app::run", "use crate::io::{Summary, scene::Scene as S};\n#[cfg(test)] mod tests { use super::*; }"),
        file("app::sweep", "use super::run; fn f() -> r#type { crate::io::scene::read(); run::x() }"),
    ];
    let g = graph(&files);
    assert_eq!(edges(&g, "io::scene"), Vec::<String>::new());
    assert_eq!(edges(&g, "io::summary"), ["io::scene"]);
    // `io::Summary` is followed through io's door to io::summary
    assert_eq!(edges(&g, "app::run"), ["io::scene", "io::summary"]);
    assert_eq!(edges(&g, "app::sweep"), ["app::run", "io::scene"]);
    assert_eq!(edges(&g, "io"), Vec::<String>::new());
    assert!(all_circles(&g).is_empty());
    assert!(upward_arrows(&g, &["io", "app"]).is_empty());
}

/// An upward arrow, a circle between files and a circle between folders are each found.
#[test]
fn the_check_finds_an_upward_arrow_and_circles() {
    let files = [
        file("io", "pub mod scene;"),
        file("io::scene", "use crate::app::run::Loaded;"),
        file("app", "pub mod run; pub mod path; pub mod sweep; pub mod plot;"),
        file("app::run", "use super::path::solve;"),
        file("app::path", "pub fn solve() { super::run::load() }"),
        file("studies", "pub mod report; pub mod bench;"),
        file("studies::report", "pub mod a; pub mod b;"),
        file("studies::report::a", "use crate::studies::bench::x;"),
        file("studies::report::b", ""),
        file("studies::bench", "use crate::studies::report::b::y;"),
    ];
    let g = graph(&files);
    assert_eq!(upward_arrows(&g, &["io", "app", "studies"]), ["io::scene → app::run points up (io below app)"]);
    assert_eq!(upward_arrows(&g, &["io", "app"])[0], "studies is in no layer of [\"io\", \"app\"]");
    let circles = all_circles(&g);
    // report::a → bench → report::b: no circle of files, a circle of folders
    let expected = [
        "app::path, app::run (app::path → app::run, app::run → app::path)",
        "studies::bench, studies::report (studies::bench → studies::report, studies::report → studies::bench)",
    ];
    assert_eq!(circles, expected);
}
