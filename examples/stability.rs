//! Issue 5's stability table: every stiff and extreme case × every solver, the locking of P1
//! displacements against ν, and the units check. Prints the tables and rewrites the block
//! between `<!-- stability:begin -->` and `<!-- stability:end -->` in docs/stability.md.
//!
//! ```text
//! cargo run --release --example stability            # a quarter of an hour on 2 cores (the P2 locking rows: 157k dofs, 4 GB)
//! cargo run --release --example stability -- --print # print only, leave docs/stability.md alone
//! ```

use saddle::studies::stability::{
    Outcome, all_solvers, cases, locking, locking_markdown, markdown, study, units_check, units_markdown,
};
use std::time::Instant;

fn main() {
    let print_only = std::env::args().any(|a| a == "--print");
    let t0 = Instant::now();
    let cases = cases();
    let n: usize = cases.iter().map(|c| c.solvers.len()).sum();
    let mut done = 0;
    let rows = study(&cases, |r| {
        done += 1;
        let what = match &r.outcome {
            Outcome::Returned { summary, .. } => {
                format!("{:?}, {} iterations", summary.stop_reason, summary.iterations)
            }
            Outcome::SceneError(_) => "scene error".into(),
            Outcome::SolveError(_) => "error".into(),
        };
        eprintln!("[{done}/{n}] case {} {} / {}: {what}", r.case.group, r.case.label, r.solver);
    });
    let table = markdown(&rows);
    eprintln!("locking study (Newton, two meshes)...");
    let lock = locking_markdown(&locking(&[0.3, 0.49, 0.499, 0.4999]));
    let units: Vec<_> =
        all_solvers().iter().map(|s| units_check(s.as_ref(), 1e9, 1e-3).expect("units case runs")).collect();
    let units = units_markdown(&units);
    let block = format!(
        "Measured by `cargo run --release --example stability` ({:.0} s on this machine) on the small \
         default scene (12×12×6 cells graded 3, 5 184 tetrahedra, theory §6 with the edit in the case column; rows marked p2: the P2 element on 6×6×3 cells, the same nodes). \
         KKT is the relative residual recomputed from the returned solution; \"U vs Newton\" is the relative \
         difference from Newton's U on the same case.\n\n{table}\n**Units** (case 3: stresses ×1e9, lengths ×1e-3, \
         force ×1e3): relative deviation of u/10⁻³ and σ/10⁹ from the solution in the default units.\n\n{units}\n\
         **Locking** (case 2): U of Newton on the small mesh and on the twice finer mesh.\n\n{lock}",
        t0.elapsed().as_secs_f64()
    );
    println!("{block}");
    if !print_only {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/stability.md");
        let page = std::fs::read_to_string(&path).expect("docs/stability.md");
        let (begin, end) = ("<!-- stability:begin -->", "<!-- stability:end -->");
        match (page.find(begin), page.find(end)) {
            (Some(b), Some(e)) if b < e => {
                let new = format!("{}{begin}\n{block}\n{}", &page[..b], &page[e..]);
                std::fs::write(&path, new).expect("write docs/stability.md");
                eprintln!("docs/stability.md updated");
            }
            _ => eprintln!("docs/stability.md has no {begin} … {end} block; printed only"),
        }
    }
}
