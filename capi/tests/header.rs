//! The committed C header is what cbindgen 0.29 generates from the crate today.
//! Regenerate it with `YGG_BLESS_HEADER=1 cargo test -p ygg-capi --test header`.

use std::path::Path;

#[test]
fn header_is_current() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config =
        cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_config(config)
        .with_crate(crate_dir)
        .generate()
        .expect("cbindgen generates the header")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let committed_path = crate_dir.join("include/yggdrasil.h");
    if std::env::var_os("YGG_BLESS_HEADER").is_some() {
        std::fs::write(&committed_path, &generated).expect("write the header");
        return;
    }
    let committed = std::fs::read_to_string(&committed_path).unwrap_or_default();
    assert!(
        committed == generated,
        "capi/include/yggdrasil.h is not what cbindgen generates from capi/src; run \
         `YGG_BLESS_HEADER=1 cargo test -p ygg-capi --test header` and commit the result"
    );
}
