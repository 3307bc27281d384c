//! Build script of the command-line tool: under continuous integration
//! (`CI=true`), the tests that need realistic data run as ordinary tests
//! (`cfg(ci)`) and fail when it is missing; elsewhere they are ignored with
//! the reason (tests/nbrdf.rs).

fn main() {
    println!("cargo::rustc-check-cfg=cfg(ci)");
    println!("cargo::rerun-if-env-changed=CI");
    if std::env::var("CI").is_ok_and(|v| v == "true" || v == "1") {
        println!("cargo::rustc-cfg=ci");
    }
}
