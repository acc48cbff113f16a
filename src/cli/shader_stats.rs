//! `contrastxr bench --shader-stats`: the driver compiler's statistics of the frame's
//! per-pixel shaders, as text after the bench's rows or in its JSON.

use contrastxr::gpu::{ShaderStatistics, StatisticValue};

/// The statistics, or why there are none.
pub type ShaderReport = Result<Vec<ShaderStatistics>, String>;

pub fn text(report: &ShaderReport) -> String {
    let all = match report {
        Err(why) => return format!("shader statistics: none: {why}\n"),
        Ok(all) => all,
    };
    let mut s = String::from("shader statistics (the driver's compiler, by its own names):\n");
    for shader in all {
        for e in &shader.executables {
            let stats: Vec<String> = e
                .statistics
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect();
            s += &format!(
                "  {} [{}, subgroup {}]: {}\n",
                shader.shader,
                e.executable,
                e.subgroup_size,
                stats.join(", ")
            );
        }
    }
    s
}

fn json_value(v: StatisticValue) -> serde_json::Value {
    match v {
        StatisticValue::Bool(b) => b.into(),
        StatisticValue::Int(i) => i.into(),
        StatisticValue::Uint(u) => u.into(),
        StatisticValue::Float(x) => x.into(),
        StatisticValue::Unknown => serde_json::Value::Null,
    }
}

/// `"shader_statistics"`: a list of shaders, each with its executables' statistics (numbers
/// and booleans as JSON's, null for a format not known), or `"shader_statistics_error"`.
pub fn json(report: &ShaderReport, into: &mut serde_json::Map<String, serde_json::Value>) {
    let all = match report {
        Err(why) => {
            into.insert("shader_statistics_error".into(), why.clone().into());
            return;
        }
        Ok(all) => all,
    };
    let shaders = all.iter().map(|shader| {
        let executables = shader.executables.iter().map(|e| {
            let statistics: serde_json::Map<String, serde_json::Value> = e
                .statistics
                .iter()
                .map(|(k, v)| (k.clone(), json_value(*v)))
                .collect();
            serde_json::json!({
                "name": e.executable,
                "subgroup_size": e.subgroup_size,
                "statistics": statistics,
            })
        });
        serde_json::json!({ "shader": shader.shader, "executables": executables.collect::<Vec<_>>() })
    });
    into.insert(
        "shader_statistics".into(),
        shaders.collect::<Vec<_>>().into(),
    );
}
