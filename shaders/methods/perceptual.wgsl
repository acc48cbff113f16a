// `perceptual` (docs/algorithm.md, The perceptual method; beyond the paper): the paper's
// colour change r (its output, `paper`, from the paper's method_scaled, appended after this
// file, run only for groups of pixels not all at the target) spent where the eye gains most.
// A pixel already seen at the target contrast is left alone; otherwise the most visible of
// the paper's colour and the colours r away in 18 fixed CIELAB directions (clipped; dropped if
// clipping lengthened the change), then back toward the display colour to the least change
// that reaches the target as the image stores it (8 halvings). c' is the model's perceived
// contrast, evaluated from the view's tables in `perceptual` (PERCEPTUAL_* in
// src/gpu/core/interface.rs), as src/algorithm/perception/tables.rs does in f32.

// How far a candidate's CIELAB change may pass r and still count as within it (the CPU
// reference's BUDGET_SLACK).
const BUDGET_SLACK: f32 = 1e-6;
const BISECTION_STEPS: u32 = 8u;
const LOG10_E: f32 = 0.4342944819;

// The view's model, the header of `perceptual` (PERCEPTUAL_AT_*), read once per invocation:
// constant indices into the fixed-size table are proved in range, so no load is checked or
// repeated.
struct Model {
    // Linear RGB -> LMS, by rows, and RGB -> luminance.
    lms_0: vec3<f32>,
    lms_1: vec3<f32>,
    lms_2: vec3<f32>,
    luminance: vec3<f32>,
    half_peak: f32,
    world: f32,
    log_min_luminance: f32,
    goal: f32,
    // The target the lower bound of c' must reach (surely_at_target).
    sure_goal: f32,
    frequencies: u32,
    log_y_first: f32,
    entries_per_log_y: f32,
}

const_assert PERCEPTUAL_AT_RGB_TO_LMS == 0u && PERCEPTUAL_AT_RGB_TO_LUMINANCE == 9u;
const_assert PERCEPTUAL_AT_HALF_PEAK == 12u && PERCEPTUAL_AT_WORLD == 13u && PERCEPTUAL_AT_LOG_MIN_LUMINANCE == 14u;
const_assert PERCEPTUAL_AT_TARGET == 15u && PERCEPTUAL_AT_FREQUENCIES == 16u;
const_assert PERCEPTUAL_AT_LOG_Y_FIRST == 17u && PERCEPTUAL_AT_ENTRIES_PER_LOG_Y == 18u && PERCEPTUAL_AT_SURE_TARGET == 19u;

fn read_model() -> Model {
    let h0 = perceptual[0];
    let h1 = perceptual[1];
    let h2 = perceptual[2];
    let h3 = perceptual[3];
    let h4 = perceptual[4];
    return Model(h0.xyz, vec3<f32>(h0.w, h1.xy), vec3<f32>(h1.zw, h2.x), h2.yzw, h3.x, h3.y, h3.z, h3.w, h4.w, u32(h4.x), h4.y, h4.z);
}

fn cone_responses(m: Model, c: Colours) -> Colours {
    return Colours(row_times(m.lms_0, c), row_times(m.lms_1, c), row_times(m.lms_2, c));
}

// The world's light behind four pixels as it reaches the eye (t W): its cone responses and
// luminance, the same for every candidate colour, and the model.
struct World {
    lms: Colours,
    luminance: vec4<f32>,
    model: Model,
}

fn world_of(m: Model, background: Colours) -> World {
    let tw = m.world;
    let lms = cone_responses(m, background);
    return World(Colours(tw * lms[0], tw * lms[1], tw * lms[2]), tw * row_times(m.luminance, background), m);
}

// The three channels' sensitivities of frequency f at table position i + t (linear between
// entries) for each pixel: x, y, z of each vec4 (achromatic, red-green, yellow-violet).
struct Sensitivities {
    achromatic: vec4<f32>,
    red_green: vec4<f32>,
    yellow_violet: vec4<f32>,
}

fn entry(f: u32, i: u32, t: f32) -> vec3<f32> {
    let at = PERCEPTUAL_HEADER_WORDS / 4u + f * PERCEPTUAL_TABLE_LEN + i;
    let lo = perceptual[at].xyz;
    return lo + t * (perceptual[at + 1u].xyz - lo);
}

fn sensitivities(f: u32, i: vec4<u32>, t: vec4<f32>) -> Sensitivities {
    let s = transpose(mat4x3<f32>(entry(f, i.x, t.x), entry(f, i.y, t.y), entry(f, i.z, t.z), entry(f, i.w, t.w)));
    return Sensitivities(s[0], s[1], s[2]);
}

// A cone contrast ratio, 0 where there is no light.
fn ratio(a: vec4<f32>, m: vec4<f32>) -> vec4<f32> {
    return select(vec4<f32>(0.0), a / m, m > vec4<f32>(0.0));
}

// The pattern four linear display colours make over their world (alternating between the
// world and world + display): its cone responses' amplitude and mean, its mean luminance, and
// its physical RMS cone contrast c, which bounds c' (c' = c max(1 - 1/C, 0) <= c).
struct Pattern {
    amp: Colours,
    mean: Colours,
    luminance: vec4<f32>,
    c: vec4<f32>,
}

fn pattern(display: Colours, world: World) -> Pattern {
    let m = world.model;
    let half_peak = m.half_peak;
    let lms = cone_responses(m, display);
    let amp = Colours(half_peak * lms[0], half_peak * lms[1], half_peak * lms[2]);
    let mean = world.lms + amp;
    let y = world.luminance + half_peak * row_times(m.luminance, display);
    let k0 = ratio(amp[0], mean[0]);
    let k1 = ratio(amp[1], mean[1]);
    let k2 = ratio(amp[2], mean[2]);
    return Pattern(amp, mean, y, sqrt((k0 * k0 + k1 * k1 + k2 * k2) * (1.0 / 3.0)));
}

// The pattern's opponent channels (castleCSF's K), each against the achromatic mean: one
// column per channel (achromatic, red-green, yellow-violet).
fn opponent_contrasts(p: Pattern) -> Colours {
    let amp = p.amp;
    let m1 = abs(p.mean[0] + p.mean[1]);
    let inv_m1 = select(vec4<f32>(0.0), 1.0 / m1, m1 > vec4<f32>(0.0));
    return Colours(abs(amp[0] + amp[1]) * inv_m1, abs(amp[0] - 2.3112 * amp[1]) * inv_m1, abs(50.9875 * amp[2] - amp[0] - amp[1]) * inv_m1);
}

// Each pixel's least sensitivities by its luminance band (the bands' floors rise): band k's
// where Y is at or above its floor, none below the first.
fn raised(s: Sensitivities, y: vec4<f32>, band: vec4<f32>) -> Sensitivities {
    let inside = y >= vec4<f32>(band.x);
    return Sensitivities(select(s.achromatic, vec4<f32>(band.y), inside), select(s.red_green, vec4<f32>(band.z), inside), select(s.yellow_violet, vec4<f32>(band.w), inside));
}

fn least_sensitivities(y: vec4<f32>) -> Sensitivities {
    let at = PERCEPTUAL_AT_BANDS / 4u;
    var s = Sensitivities(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    s = raised(s, y, perceptual[at]);
    s = raised(s, y, perceptual[at + 1u]);
    s = raised(s, y, perceptual[at + 2u]);
    s = raised(s, y, perceptual[at + 3u]);
    s = raised(s, y, perceptual[at + 4u]);
    s = raised(s, y, perceptual[at + 5u]);
    s = raised(s, y, perceptual[at + 6u]);
    s = raised(s, y, perceptual[at + 7u]);
    return s;
}

const_assert PERCEPTUAL_BANDS == 8u && PERCEPTUAL_AT_BANDS % 4u == 0u;

// Where four patterns are surely seen at the target: c' from their bands' least sensitivities
// (a lower bound of c', src/algorithm/perception/target_bound.rs) reaches the target with a
// margin. No logarithm, no lookup; false where c' must decide.
fn surely_at_target(p: Pattern, m: Model) -> vec4<bool> {
    let s = least_sensitivities(p.luminance);
    let d = opponent_contrasts(p);
    let a = d[0] * s.achromatic;
    let rg = d[1] * s.red_green;
    let yv = d[2] * s.yellow_violet;
    let over = p.c - vec4<f32>(m.sure_goal);
    // c (1 - 1/C) >= target  <=>  C (c - target) >= c, for c > target; squared.
    return (over > vec4<f32>(0.0)) & ((a * a + rg * rg + yv * yv) * over * over >= p.c * p.c);
}

// Whether four display colours are seen at the target over their world: surely by the bound,
// else by c' (only those the bound leaves open make its lookups).
fn at_target(display: Colours, world: World) -> vec4<bool> {
    let p = pattern(display, world);
    let goal = vec4<f32>(world.model.goal);
    let sure = surely_at_target(p, world.model);
    let open = !sure & (p.c >= goal);
    return sure | (select(vec4<f32>(-1.0), perceived_of(p, world.model, open), open) >= goal);
}

// c' of four patterns: c less its threshold, by castleCSF at the pattern's mean luminance,
// averaged over the frame's frequencies. Only where `wanted`: where no pixel wants it, 0
// without the tables (a caller that knows c' cannot matter there, from c, skips the lookups).
fn perceived_of(p: Pattern, m: Model, wanted: vec4<bool>) -> vec4<f32> {
    if (!any(wanted)) {
        return vec4<f32>(0.0);
    }
    let log_y = max(LOG10_E * log(max(p.luminance, vec4<f32>(1e-30))), vec4<f32>(m.log_min_luminance));
    let d = opponent_contrasts(p);
    let d1 = d[0];
    let d2 = d[1];
    let d3 = d[2];
    let last = f32(PERCEPTUAL_TABLE_LEN - 1u);
    let x = clamp((log_y - m.log_y_first) * m.entries_per_log_y, vec4<f32>(0.0), vec4<f32>(last));
    let i = min(vec4<u32>(x), vec4<u32>(PERCEPTUAL_TABLE_LEN - 2u));
    let t = x - vec4<f32>(i);
    let n = m.frequencies;
    var sum = vec4<f32>(0.0);
    for (var f = 0u; f < n; f++) {
        let s = sensitivities(f, i, t);
        let a = d1 * s.achromatic;
        let rg = d2 * s.red_green;
        let yv = d3 * s.yellow_violet;
        let multiple = sqrt(a * a + rg * rg + yv * yv);
        let kept = select(vec4<f32>(0.0), max(1.0 - 1.0 / multiple, vec4<f32>(0.0)), multiple > vec4<f32>(0.0));
        sum += p.c * kept;
    }
    return sum / f32(n);
}

// c' where it may reach `at_least` (c >= at_least), -1 elsewhere (it cannot: c' <= c).
fn perceived_from(display: Colours, world: World, at_least: vec4<f32>) -> vec4<f32> {
    let p = pattern(display, world);
    let may = p.c >= at_least;
    return select(vec4<f32>(-1.0), perceived_of(p, world.model, may), may);
}

// The 18 directions, unit vectors in CIELAB (L*, a*, b*): the 6 axes, the 8 diagonals of the
// cube, the 4 diagonals of the a*b* plane.
fn direction(k: u32) -> vec3<f32> {
    let s3 = 0.57735026919;
    let s2 = 0.70710678119;
    if (k < 6u) {
        let axis = k / 2u;
        let sign = select(1.0, -1.0, (k & 1u) != 0u);
        return sign * vec3<f32>(f32(axis == 0u), f32(axis == 1u), f32(axis == 2u));
    }
    if (k < 14u) {
        let j = k - 6u;
        return s3 * vec3<f32>(select(1.0, -1.0, (j & 4u) != 0u), select(1.0, -1.0, (j & 2u) != 0u), select(1.0, -1.0, (j & 1u) != 0u));
    }
    let j = k - 14u;
    return s2 * vec3<f32>(0.0, select(1.0, -1.0, (j & 2u) != 0u), select(1.0, -1.0, (j & 1u) != 0u));
}

// A CIELAB step (Delta E units) as a step in the scaled space, per pixel of length r.
fn scaled_step(u: vec3<f32>, r: vec4<f32>) -> Colours {
    return scaled_steps(vec4<f32>(u.x), vec4<f32>(u.y), vec4<f32>(u.z), r);
}

// The same with a direction per pixel (components ux, uy, uz): the same operations, so that a
// candidate made again from its index is the one the search judged.
fn scaled_steps(ux: vec4<f32>, uy: vec4<f32>, uz: vec4<f32>, r: vec4<f32>) -> Colours {
    return Colours(r * (ux / 50.0), r * (uy / 128.0), r * (uz / 128.0));
}

// The best candidate so far, per pixel: its index (a direction, or PAPER_CANDIDATE), its
// CIELAB change and c'. Its colours are made again from the index after the search
// (`candidate_colours`), which holds fewer values through it.
const PAPER_CANDIDATE: u32 = 18u;

struct Best {
    index: vec4<u32>,
    change: vec4<f32>,
    perceived: vec4<f32>,
}

fn keep_better(best: Best, index: u32, change: vec4<f32>, perceived: vec4<f32>, valid: vec4<bool>) -> Best {
    // Changes within the slack are equal: unclipped, every candidate's is the budget.
    let smaller = change < best.change - BUDGET_SLACK;
    let better = valid & ((perceived > best.perceived) | ((perceived == best.perceived) & smaller));
    return Best(select(best.index, vec4<u32>(index), better), select(best.change, change, better), select(best.perceived, perceived, better));
}

// A direction's candidate: the colour `budget` away from d (scaled) along it, clipped in linear
// RGB, and its scaled colour as asked (`candidate` does not convert the clipped colour back;
// `candidate_colours` does, where clipping moved it).
struct Candidate {
    colour: Colours,
    scaled: Colours,
    clipped: vec4<bool>,
}

fn candidate(lab: Colours) -> Candidate {
    let unclipped = scaled_to_linear(lab);
    let colour = clip(unclipped);
    let clipped = (colour[0] != unclipped[0]) | (colour[1] != unclipped[1]) | (colour[2] != unclipped[2]);
    return Candidate(colour, lab, clipped);
}

// The linear and scaled colours of each pixel's best candidate (index per pixel); the paper's
// colour is `paper`.
fn candidate_colours(index: vec4<u32>, d: Colours, budget: vec4<f32>, paper: Colours) -> Candidate {
    let u = group_of(direction(index.x), direction(index.y), direction(index.z), direction(index.w));
    let c = candidate(d + scaled_steps(u[0], u[1], u[2], budget));
    let is_paper = index == vec4<u32>(PAPER_CANDIDATE);
    let colour = pick(c.colour, paper, is_paper);
    return Candidate(colour, pick(c.scaled, linear_to_scaled(colour), c.clipped | is_paper), c.clipped);
}

// The pixels the method may change: those not seen at the target already (`alone` in
// method_perceptual below: the same functions of the same values), for its `classify`.
fn perceptual_may_change(display: Colours, bg: Background) -> vec4<bool> {
    return !at_target(display, world_of(read_model(), bg.linear));
}

fn method_perceptual(display: Colours, d: Colours, bg: Background) -> Perceived {
    let world = world_of(read_model(), bg.linear);
    let goal = world.model.goal;
    let unchanged = Enhanced(display, vec4<bool>(false));
    let alone = perceived_from(display, world, vec4<f32>(goal)) >= vec4<f32>(goal);
    if (all(alone)) {
        // Seen at the target already: the paper's budget is not needed.
        return Perceived(unchanged, vec4<u32>(PERCEIVED_LEFT_ALONE));
    }
    let paper = scaled_output(display, d, bg.scaled);
    let paper_scaled = linear_to_scaled(paper.linear);
    // The paper's change; none where the paper leaves the pixel.
    let budget = select(vec4<f32>(0.0), delta_e(d, paper_scaled), paper.changed);
    let none = !alone & (budget == vec4<f32>(0.0));
    let kind = select(select(vec4<u32>(0u), vec4<u32>(PERCEIVED_OUT_OF_REACH), none), vec4<u32>(PERCEIVED_LEFT_ALONE), alone);
    if (all(alone | none)) {
        return Perceived(unchanged, kind);
    }
    var best = Best(vec4<u32>(PAPER_CANDIDATE), budget, perceived_from(paper.linear, world, vec4<f32>(0.0)));
    // The benchmark's ablation of the directions leaves the paper's colour alone.
    let directions = select(18u, 0u, ablated(ABLATE_DIRECTIONS));
    for (var k = 0u; k < directions; k++) {
        let lab = d + scaled_step(direction(k), budget);
        let cand = candidate(lab);
        // Only a candidate whose c reaches the best c' so far may beat it (c' <= c).
        let p = pattern(cand.colour, world);
        let may = p.c >= best.perceived;
        // Clipping in linear RGB may lengthen the change beyond the paper's: then it is no
        // candidate. Unclipped, the change is the budget.
        var change = budget;
        if (any(cand.clipped & may)) {
            change = select(budget, delta_e(d, linear_to_scaled(cand.colour)), cand.clipped);
        }
        let valid = change <= budget + BUDGET_SLACK;
        let wanted = may & valid;
        let perceived = select(vec4<f32>(-1.0), perceived_of(p, world.model, wanted), wanted);
        best = keep_better(best, k, change, perceived, valid);
    }
    let chosen = candidate_colours(best.index, d, budget, paper.linear);
    let reached = best.perceived >= vec4<f32>(goal);
    var out = chosen.colour;
    if (any(reached & !alone & !none) && !ablated(ABLATE_BISECTION)) {
        // Back toward D on the straight CIELAB line: c'(D) < target <= c'(1).
        var lo = vec4<f32>(0.0);
        var hi = vec4<f32>(1.0);
        let span = chosen.scaled - d;
        for (var step = 0u; step < BISECTION_STEPS; step++) {
            let mid = 0.5 * (lo + hi);
            let colour = clip(scaled_to_linear(d + per_pixel(mid, span)));
            // Judged as stored, so that the pixel shown reaches the target.
            let shown = decode_stored(quantised(encode_stored(colour)));
            // (The bound seldom settles these: the search ends near the target.)
            let ok = perceived_from(shown, world, vec4<f32>(goal)) >= vec4<f32>(goal);
            hi = select(hi, mid, ok);
            lo = select(mid, lo, ok);
            out = pick(out, colour, ok);
        }
    }
    let moved = !alone & !none;
    let moved_kind = select(vec4<u32>(PERCEIVED_OUT_OF_REACH), vec4<u32>(PERCEIVED_TO_TARGET), reached);
    // A pixel not moved keeps its words (enhance_group), whatever `out` holds there.
    return Perceived(Enhanced(out, moved), select(kind, moved_kind, moved));
}
