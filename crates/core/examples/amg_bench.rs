//! Times AMG-preconditioned CG against sparse Cholesky on the elastic stiffness of a scene
//! (its `[yield]`, `[obstacle]` and `[solver]` tables are ignored).
//!
//! ```text
//! cargo run --release -p saddle-core --example amg_bench -- examples/johnson.toml [cells] [mode] [θ] [degree]
//! #   cells: e.g. 48,48,24 (default: the scene's); mode: amg | direct | both (default amg);
//! #   θ: strength threshold (default 0.02); degree: Chebyshev degree (default 2)
//! ```
//!
//! The right-hand side is a unit downward body force per node (b = −1 on z components). Peak
//! memory is the process's high-water mark (VmHWM), so run `amg` and `direct` separately to
//! compare memory.

use saddle_core::lagrangian::{Lagrangian, Material};
use saddle_core::{AmgParams, Csr, DofLayout, Pcg, Scene, SmoothedAggregation, SparseCholesky};
use std::path::Path;
use std::time::Instant;

fn peak_memory_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM")).map(|l| l.to_string()))
        .and_then(|l| l.split_whitespace().nth(1).and_then(|k| k.parse::<f64>().ok()))
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).map_or("examples/johnson.toml", |s| s.as_str());
    let mut scene: toml::Table = std::fs::read_to_string(path)?.parse()?;
    for key in ["yield", "obstacle", "solver"] {
        scene.remove(key);
    }
    if let Some(cells) = args.get(2).filter(|s| *s != "-") {
        let cells: Vec<toml::Value> =
            cells.split(',').map(|c| c.trim().parse::<i64>().map(toml::Value::Integer)).collect::<Result<_, _>>()?;
        scene["mesh"].as_table_mut().ok_or("no [mesh] table")?.insert("cells".into(), toml::Value::Array(cells));
    }
    let mode = args.get(3).map_or("amg", |s| s.as_str());
    let mut params = AmgParams::default();
    if let Some(t) = args.get(4) {
        params.strength_threshold = t.parse()?;
    }
    if let Some(d) = args.get(5) {
        params.smoother_degree = d.parse()?;
    }

    let t = Instant::now();
    let scene = Scene::from_toml(&toml::to_string(&scene)?, Path::new(path))?;
    let (l, _) = scene.into_problem()?;
    let c = l.elasticity().stiffness_matrix();
    let values = l.stiffness(Material::Uniform(&c));
    let n = l.n_dofs();
    let mut b = vec![0.0; n];
    for d in &l.dofs().dof {
        if d[2] != saddle_core::dofs::FIXED {
            b[d[2] as usize] = -1.0;
        }
    }
    println!("{path}: {n} dofs, {} nnz (lower), assembly {:.2} s", l.pattern().nnz(), t.elapsed().as_secs_f64());

    let amg_solution = if mode == "amg" || mode == "both" {
        let t = Instant::now();
        let a = Csr::from_symmetric_lower(l.pattern(), &values);
        let layout = DofLayout::new(l.dofs(), &l.mesh().nodes)?;
        let t_csr = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let amg = SmoothedAggregation::new(&a, &layout, &params)?;
        let t_setup = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut pcg = Pcg::new(n);
        let mut x = vec![0.0; n];
        let rep = pcg.solve(&a, &amg, &b, &mut x, 1e-8, 500)?;
        let t_solve = t.elapsed().as_secs_f64();
        println!(
            "AMG θ = {}, degree {}: levels {:?}, operator complexity {:.2}",
            params.strength_threshold,
            params.smoother_degree,
            amg.level_info().iter().map(|i| i.n).collect::<Vec<_>>(),
            amg.operator_complexity()
        );
        println!(
            "AMG-PCG: CSR {t_csr:.2} s, set-up {t_setup:.2} s, solve {t_solve:.2} s ({} iterations, residual {:.1e}, \
             converged {}), total {:.2} s, peak memory {:.0} MB",
            rep.iterations,
            rep.relative_residual,
            rep.converged,
            t_csr + t_setup + t_solve,
            peak_memory_mb()
        );
        Some(x)
    } else {
        None
    };
    if mode == "direct" || mode == "both" {
        let t = Instant::now();
        let mut chol = SparseCholesky::analyse(l.pattern(), "stiffness")?;
        let t_an = t.elapsed().as_secs_f64();
        let t = Instant::now();
        chol.factorise(l.pattern(), &values)?;
        let t_fac = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut y = b.clone();
        chol.solve(&mut y);
        let t_sol = t.elapsed().as_secs_f64();
        let versus_amg = amg_solution.map_or(String::new(), |x| {
            let err = x.iter().zip(&y).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt()
                / y.iter().map(|q| q * q).sum::<f64>().sqrt();
            format!("; AMG vs Cholesky relative error {err:.1e}")
        });
        println!(
            "Cholesky: analyse {t_an:.2} s, factorise {t_fac:.2} s, solve {t_sol:.2} s, total {:.2} s \
             (nnz(L) = {}){versus_amg}; peak memory {:.0} MB",
            t_an + t_fac + t_sol,
            chol.nnz_l(),
            peak_memory_mb()
        );
    }
    Ok(())
}
