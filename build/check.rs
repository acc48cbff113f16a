//! The interface checks: what a parsed shader declares (read from naga's module by
//! build/parse.rs) against src/gpu/core/interface.rs, the bindings, the push-constant
//! block's layout, the tile list's header and the entry points' workgroup sizes, and the GLSL's
//! uniforms and bindings. Each failure fails the build with a message naming both sides.

use crate::interface::*;

/// What the checks read of a parsed shader, in the module's order.
#[derive(Clone, Debug, Default)]
pub struct ShaderFacts {
    pub globals: Vec<Global>,
    /// The members of every type named `TileList` (`None`: not a struct).
    pub tile_lists: Vec<Option<Vec<Member>>>,
    /// Every entry point's name and workgroup size.
    pub entry_points: Vec<(String, [u32; 3])>,
}

/// A global variable of a shader.
#[derive(Clone, Debug)]
pub struct Global {
    /// Its name (`?` for none).
    pub name: String,
    /// Its group, binding number and kind, where it has a binding.
    pub binding: Option<(u32, u32, BindingKind)>,
    /// Where it is the push-constant block: its members and size (`None`: not a struct).
    pub immediate: Option<Option<(Vec<Member>, u32)>>,
}

/// A struct member's name (`?` for none) and byte offset.
#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    pub name: String,
    pub offset: u32,
}

/// Fails the build where a parsed shader disagrees with src/gpu/core/interface.rs: its
/// bindings, its push-constant block's layout, its tile list's header, or its entry points'
/// workgroup sizes (each message names both sides).
pub fn check_interface(name: &str, facts: &ShaderFacts) {
    let here = format!("{name}.wgsl vs src/gpu/core/interface.rs");
    for var in &facts.globals {
        let var_name = &var.name;
        if let Some((group, number, kind)) = var.binding {
            let b = BINDINGS
                .iter()
                .find(|b| group == 0 && b.number == number)
                .unwrap_or_else(|| {
                    panic!(
                        "{here}: `{var_name}` at group {group} binding {number} is not in BINDINGS"
                    )
                });
            assert_eq!(
                var_name, b.name,
                "{here}: binding {} is `{var_name}` in the shader, `{}` in BINDINGS",
                b.number, b.name
            );
            assert_eq!(
                kind, b.kind,
                "{here}: binding {} (`{var_name}`) is a {kind:?} in the shader, a {:?} in BINDINGS",
                b.number, b.kind
            );
        }
        if let Some(block) = &var.immediate {
            check_params(&here, block.as_ref());
        }
    }
    for tile_list in &facts.tile_lists {
        check_tile_list(&here, tile_list.as_deref());
    }
    for (ep, ep_size) in &facts.entry_points {
        let (_, size) = WORKGROUPS
            .iter()
            .find(|(n, _)| n == ep)
            .unwrap_or_else(|| panic!("{here}: entry point `{ep}` is not in WORKGROUPS"));
        assert_eq!(
            ep_size, size,
            "{here}: `{ep}` has workgroup size {ep_size:?} in the shader, {size:?} in WORKGROUPS"
        );
    }
}

/// The push-constant block against PARAMS: the fields by name and order, their offsets, the
/// size.
pub fn check_params(here: &str, block: Option<&(Vec<Member>, u32)>) {
    let Some((members, span)) = block else {
        panic!("{here}: the push constants are not a struct");
    };
    let (offsets, size) = params_layout();
    let names: Vec<_> = members.iter().map(|m| m.name.as_str()).collect();
    let wanted: Vec<_> = PARAMS.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, wanted, "{here}: Params fields differ from PARAMS");
    for (m, (&offset, (field, _))) in members.iter().zip(offsets.iter().zip(PARAMS)) {
        assert_eq!(
            m.offset, offset,
            "{here}: Params.{field} at byte {} in the shader, {offset} in PARAMS",
            m.offset
        );
    }
    assert_eq!(
        *span, size,
        "{here}: Params is {span} bytes in the shader, {size} in PARAMS"
    );
}

/// The tile list's header against TILE_LIST_DISPATCH_OFFSET, TILE_LIST_DRAW_OFFSET and
/// TILE_LIST_HEADER_WORDS.
pub fn check_tile_list(here: &str, members: Option<&[Member]>) {
    let Some(members) = members else {
        panic!("{here}: TileList is not a struct");
    };
    let offset = |field: &str| {
        let m = members.iter().find(|m| m.name == field);
        m.unwrap_or_else(|| panic!("{here}: TileList has no `{field}`"))
            .offset
    };
    let groups = u64::from(offset("groups"));
    assert_eq!(groups, TILE_LIST_DISPATCH_OFFSET, "{here}: TileList.groups at byte {groups} in the shader, TILE_LIST_DISPATCH_OFFSET {TILE_LIST_DISPATCH_OFFSET}");
    let draw = u64::from(offset("draw"));
    assert_eq!(draw, TILE_LIST_DRAW_OFFSET, "{here}: TileList.draw at byte {draw} in the shader, TILE_LIST_DRAW_OFFSET {TILE_LIST_DRAW_OFFSET}");
    let index = u64::from(offset("index"));
    assert_eq!(index, TILE_LIST_HEADER_WORDS * 4, "{here}: TileList.index at byte {index} in the shader, TILE_LIST_HEADER_WORDS {TILE_LIST_HEADER_WORDS} words");
}

/// The PARAMS field a uniform of naga's GLSL stands for (its index in PARAMS) and the byte
/// offset it must have there, failing the build where the uniform is no PARAMS field or sits
/// at another offset. `path` is the uniform's name (`_immediates_binding_cs.lambda_e`,
/// `...map_00_[1]`), `offset` the offset naga reports.
pub fn gl_uniform_param(here: &str, path: &str, offset: u32) -> (usize, u32) {
    let field = path
        .split_once('.')
        .map(|(_, f)| f.split('[').next().unwrap_or(f))
        .unwrap_or_else(|| panic!("{here}: uniform `{path}` is not a field of Params"));
    // naga's GLSL namer appends `_` to a name ending in a digit (map_00 -> map_00_).
    let field = match field.strip_suffix('_') {
        Some(f) if f.ends_with(|c: char| c.is_ascii_digit()) => f,
        _ => field,
    };
    let k = PARAMS
        .iter()
        .position(|(n, _)| *n == field)
        .unwrap_or_else(|| panic!("{here}: uniform `{path}` is not in PARAMS"));
    let element = path
        .rsplit_once('[')
        .and_then(|(_, i)| i.trim_end_matches(']').parse::<u32>().ok())
        .unwrap_or(0);
    let wanted = params_layout().0[k] + 16 * element;
    assert_eq!(
        offset, wanted,
        "{here}: `{path}` at byte {offset} in the GLSL, {wanted} in PARAMS"
    );
    (k, wanted)
}

/// Fails the build where a resource an entry point uses is not declared at its binding in the
/// GLSL written for it.
pub fn check_gl_binding(here: &str, glsl: &str, name: &str, binding: u32) {
    let decl = format!("binding = {binding}");
    assert!(
        glsl.contains(&decl),
        "{here}: `{name}` is used but the GLSL declares nothing at `{decl}`"
    );
}
