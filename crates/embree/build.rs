fn main() {
    println!("cargo:rustc-link-lib=embree3");
}
