//! Shared by the tests: box meshes, and for the MPI tests a distribution of a mesh over the ranks
//! (METIS parts, nodes renumbered so each rank's owned nodes are consecutive) and a test runner
//! that ends every rank when one fails.
#![allow(dead_code)]

use saddle_core::{BoxMesh, TetMesh};

/// The structured box [0, max] cut into `cells` hexahedra of 6 tetrahedra each.
pub fn box_mesh(max: [f64; 3], cells: [usize; 3]) -> TetMesh {
    BoxMesh::new([0.0; 3], max, cells).mesh().expect("a valid box")
}

/// The flat connectivity (4 nodes per element).
pub fn connectivity(mesh: &TetMesh) -> Vec<usize> {
    mesh.tets.iter().flatten().copied().collect()
}

#[cfg(feature = "petsc")]
pub mod distributed {
    use saddle_core::TetMesh;
    use saddle_mpi::{Index, Petsc, agree, partition_elements};
    use std::collections::BTreeSet;
    use std::ops::Range;

    /// A mesh distributed over the ranks: element parts, and nodes renumbered rank after rank
    /// (a node belongs to the lowest part among its elements).
    pub struct Distribution {
        /// Element → rank.
        pub part: Vec<usize>,
        /// Old node index → new (distributed) index.
        pub new_of_old: Vec<usize>,
        /// The new node indices each rank owns.
        pub ranges: Vec<Range<usize>>,
        /// This rank.
        pub rank: usize,
    }

    impl Distribution {
        pub fn new(mesh: &TetMesh, ranks: usize, rank: usize) -> Self {
            let conn: Vec<usize> = mesh.tets.iter().flatten().copied().collect();
            let part = partition_elements(&conn, 4, ranks).expect("partition");
            let mut owner = vec![usize::MAX; mesh.nodes.len()];
            for (e, t) in mesh.tets.iter().enumerate() {
                for &n in t {
                    owner[n] = owner[n].min(part[e]);
                }
            }
            let mut order: Vec<usize> = (0..mesh.nodes.len()).collect();
            order.sort_by_key(|&n| (owner[n], n));
            let mut new_of_old = vec![0; mesh.nodes.len()];
            for (new, &old) in order.iter().enumerate() {
                new_of_old[old] = new;
            }
            let mut counts = vec![0; ranks];
            for &o in &owner {
                counts[o] += 1;
            }
            let mut ranges = Vec::with_capacity(ranks);
            let mut start = 0;
            for c in counts {
                ranges.push(start..start + c);
                start += c;
            }
            Self { part, new_of_old, ranges, rank }
        }

        /// The new node indices this rank owns.
        pub fn owned(&self) -> Range<usize> {
            self.ranges[self.rank].clone()
        }

        /// The elements this rank assembles.
        pub fn my_elements(&self) -> impl Iterator<Item = usize> + '_ {
            (0..self.part.len()).filter(move |&e| self.part[e] == self.rank)
        }

        /// The new indices of the nodes of this rank's elements that it does not own, sorted.
        pub fn ghost_nodes(&self, mesh: &TetMesh) -> Vec<usize> {
            let owned = self.owned();
            let set: BTreeSet<usize> = self
                .my_elements()
                .flat_map(|e| mesh.tets[e])
                .map(|n| self.new_of_old[n])
                .filter(|n| !owned.contains(n))
                .collect();
            set.into_iter().collect()
        }

        /// Per owned row of a field with `dim` components per node: nonzeros in owned columns
        /// and in the others (from the node adjacency of the whole mesh).
        pub fn preallocation(&self, mesh: &TetMesh, dim: usize) -> (Vec<Index>, Vec<Index>) {
            let owned = self.owned();
            let mut neighbours = vec![BTreeSet::new(); owned.len()];
            for t in &mesh.tets {
                for &a in t {
                    let a = self.new_of_old[a];
                    if owned.contains(&a) {
                        for &b in t {
                            neighbours[a - owned.start].insert(self.new_of_old[b]);
                        }
                    }
                }
            }
            let mut d = Vec::with_capacity(owned.len() * dim);
            let mut o = Vec::with_capacity(owned.len() * dim);
            for set in &neighbours {
                let inside = set.iter().filter(|n| owned.contains(n)).count();
                for _ in 0..dim {
                    d.push((dim * inside) as Index);
                    o.push((dim * (set.len() - inside)) as Index);
                }
            }
            (d, o)
        }
    }

    /// A check that fails the test with a message.
    pub fn ensure(condition: bool, message: String) -> Result<(), String> {
        if condition { Ok(()) } else { Err(message) }
    }

    /// A named test case, run on every rank.
    pub type Case<'a> = (&'a str, &'a dyn Fn(&Petsc) -> Result<(), String>);

    /// Runs the cases in order on every rank; after each, the ranks agree on failure (a case
    /// failing on any rank fails on every rank, with its message). A panic aborts every rank.
    /// Returns the process's exit code (drop the session before returning it).
    pub fn run(petsc: &Petsc, cases: &[Case]) -> std::process::ExitCode {
        std::panic::set_hook(Box::new(|info| {
            eprintln!("{info}");
            // SAFETY: MPI is initialised; ends every rank instead of leaving them in a collective.
            unsafe { saddle_mpi::mpi::ffi::MPI_Abort(saddle_mpi::mpi::ffi::RSMPI_COMM_WORLD, 2) };
        }));
        let mut failed = 0;
        for (name, case) in cases {
            match agree(petsc.world(), case(petsc)) {
                Ok(()) => {
                    if petsc.rank() == 0 {
                        println!("test {name} ({} ranks) ... ok", petsc.size());
                    }
                }
                Err(e) => {
                    failed += 1;
                    if petsc.rank() == 0 {
                        println!("test {name} ({} ranks) ... FAILED: {e}", petsc.size());
                    }
                }
            }
        }
        if petsc.rank() == 0 {
            println!("{} passed, {failed} failed ({} ranks)", cases.len() - failed, petsc.size());
        }
        if failed > 0 { std::process::ExitCode::FAILURE } else { std::process::ExitCode::SUCCESS }
    }
}
