//! Times AMG-preconditioned CG against sparse Cholesky on the elastic stiffness of a scene
//! (its `[yield]`, `[obstacle]` and `[solver]` tables are ignored).
//!
//! ```text
//! cargo run --release --example amg_bench -- examples/johnson.toml [cells] [mode] [θ] [degree]
//! #   cells: e.g. 48,48,24 (default: the scene's); mode: amg | direct | both (default amg);
//! #   θ: strength threshold (default 0.02); degree: Chebyshev degree (default 2)
//! ```
//!
//! The right-hand side is a unit downward body force per node (b = −1 on z components). Peak
//! memory is the process's high-water mark (VmHWM), so run `amg` and `direct` separately to
//! compare memory.

use saddle::core::Material;
use saddle::core::linalg::{AmgParams, Csr, LowerCsc, NearNullSpace, Pcg, SmoothedAggregation, SparseCholesky};
use saddle::core::mesh::dofs::FIXED;
use saddle::core::problem::operators::RIGID_BODY_MODES;
use saddle::io::scene::Scene;
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
    let mut scene = Scene::from_file(path.as_ref())?;
    scene.yield_surface = None;
    scene.obstacle = saddle::core::Obstacles::none();
    scene.solver = None;
    if let Some(cells) = args.get(2).filter(|s| *s != "-") {
        let cells: Vec<usize> = cells.split(',').map(|c| c.trim().parse::<usize>()).collect::<Result<_, _>>()?;
        let cells: [usize; 3] = cells.try_into().map_err(|_| "cells: three numbers, e.g. 48,48,24")?;
        scene = scene.with_cells(cells)?;
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
    let (l, _) = scene.into_problem()?;
    let p = l.element.pattern();
    let lower = LowerCsc::new(p.n(), p.col_ptr(), p.row_idx());
    let c = l.lagrangian().data.elasticity.stiffness_matrix();
    let values = l.element.stiffness(Material::Uniform(&c));
    let n = l.element.n_dofs();
    let mut b = vec![0.0; n];
    for d in &l.element.dofs().dof {
        if d[2] != FIXED {
            b[d[2] as usize] = -1.0;
        }
    }
    println!(
        "{path}: {n} dofs, {} nnz (lower), assembly {:.2} s",
        l.element.pattern().nnz(),
        t.elapsed().as_secs_f64()
    );

    let amg_solution = if mode == "amg" || mode == "both" {
        let t = Instant::now();
        let a = Csr::from_symmetric_lower(lower, &values);
        let modes = l.element.rigid_body_modes().ok_or("no rigid-body modes")?;
        let near_null = NearNullSpace::new(modes.node, modes.modes, RIGID_BODY_MODES)?;
        let t_csr = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let amg = SmoothedAggregation::new(&a, &near_null, &params)?;
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
        let mut chol = SparseCholesky::analyse(lower, "stiffness")?;
        let t_an = t.elapsed().as_secs_f64();
        let t = Instant::now();
        chol.factorise(&values)?;
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
