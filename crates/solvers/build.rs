//! With the feature `sdp`, Clarabel's semidefinite cones call BLAS and LAPACK through the `blas`
//! and `lapack` crates, which declare the routines without linking a library: link the system's.
fn main() {
    if std::env::var_os("CARGO_FEATURE_SDP").is_some() {
        println!("cargo:rustc-link-lib=lapack");
        println!("cargo:rustc-link-lib=blas");
    }
}
