//! host-sim's loaders on arbitrary bytes (issue 7, fuzz target c): PNG maps, scenario files
//! and ROS map_server maps (YAML and PGM/PNG). Anything may be refused with an error; nothing may panic or run away.
#![no_main]

use host_sim::scenario;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = scenario::decode_png(data, "fuzz");
    if let Ok(text) = std::str::from_utf8(data) {
        let _ =
            scenario::scenarios_from_str(text, |_| scenario::builtin_by_name("maze").map(|s| s.map.into()), None);
    }
    // A ROS map: YAML text, then a NUL, then the image bytes.
    if let Some(at) = data.iter().position(|&b| b == 0)
        && let Ok(yaml) = std::str::from_utf8(&data[..at])
    {
        let _ = scenario::ros_map_from(yaml, &data[at + 1..], "fuzz");
    }
});
