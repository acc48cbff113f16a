//! One seam per graphics API: the layer's session, swapchain and frame code (every file of
//! `src/layer/` outside `src/layer/graphics/`) names no graphics API's types, bindings, image
//! structures or engines; those belong to the API's folder under `src/layer/graphics/`.

use std::path::Path;

/// What only an API's folder may name.
const API_SPECIFIC: [&str; 10] = [
    "vk::",
    "ash::",
    "GRAPHICS_BINDING_",
    "GraphicsBinding",
    "SWAPCHAIN_IMAGE_",
    "SwapchainImageVulkan",
    "SwapchainImageOpenGL",
    "gpu::opengl",
    "FrameRunner",
    "app_vulkan",
];

/// The API-specific names `text` uses, with their line numbers.
fn api_specific(text: &str) -> Vec<(usize, &'static str)> {
    text.lines()
        .enumerate()
        .flat_map(|(n, line)| {
            API_SPECIFIC
                .iter()
                .filter(move |name| line.contains(*name))
                .map(move |name| (n + 1, *name))
        })
        .collect()
}

#[test]
fn the_layer_outside_its_graphics_folder_names_no_graphics_api() {
    let layer = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/layer");
    let mut found = Vec::new();
    let mut files = 0;
    for entry in std::fs::read_dir(&layer).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|x| x == "rs") {
            files += 1;
            let text = std::fs::read_to_string(&path).unwrap();
            for (line, name) in api_specific(&text) {
                found.push(format!("{}:{line}: {name}", path.display()));
            }
        }
    }
    assert!(
        files >= 20,
        "only {files} files read in {}",
        layer.display()
    );
    assert!(found.is_empty(), "{found:#?}");
}

#[test]
fn the_check_sees_an_api_named_outside_the_folder() {
    let text =
        "fn f() {}\nlet image = vk::Image::null();\nlet b: xr::GraphicsBindingOpenGLXlibKHR;\n";
    assert_eq!(
        api_specific(text),
        vec![(2, "vk::"), (3, "GraphicsBinding")]
    );
}
