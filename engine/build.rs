//! Compiles every GLSL shader in `shaders/` to SPIR-V at build time, so the
//! binary embeds them (`include_bytes!`) and a shader error is a build error
//! that names the file and line.

use std::path::{Path, PathBuf};

fn main() {
    // Read at run time, not baked in with env!(): one compiled build
    // script may serve several checkouts sharing a target folder.
    let manifest_dir = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let shader_dir = Path::new(&manifest_dir).join("../shaders");
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed={}", shader_dir.display());

    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let mut entries: Vec<_> = std::fs::read_dir(&shader_dir)
        .expect("shaders/ folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .collect();
    entries.sort();
    for path in entries {
        let kind = match path.extension().and_then(|e| e.to_str()) {
            Some("vert") => shaderc::ShaderKind::Vertex,
            Some("frag") => shaderc::ShaderKind::Fragment,
            Some("comp") => shaderc::ShaderKind::Compute,
            _ => continue, // includes (*.glsl) are pulled in by #include
        };
        println!("cargo:rerun-if-changed={}", path.display());
        let source = std::fs::read_to_string(&path).expect("readable shader");
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("utf-8 name");
        let mut options = shaderc::CompileOptions::new().expect("shaderc options");
        options.set_target_env(
            shaderc::TargetEnv::Vulkan,
            shaderc::EnvVersion::Vulkan1_3 as u32,
        );
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        options.set_warnings_as_errors();
        let dir = shader_dir.clone();
        options.set_include_callback(move |requested, _, _, _| {
            let p = dir.join(requested);
            std::fs::read_to_string(&p)
                .map(|content| shaderc::ResolvedInclude {
                    resolved_name: p.display().to_string(),
                    content,
                })
                .map_err(|e| format!("{}: {e}", p.display()))
        });
        let spirv = compiler
            .compile_into_spirv(&source, kind, name, "main", Some(&options))
            .unwrap_or_else(|e| panic!("shader {}: {e}", path.display()));
        std::fs::write(out_dir.join(format!("{name}.spv")), spirv.as_binary_u8())
            .expect("write SPIR-V");
    }
}
