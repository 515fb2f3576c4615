use super::*;
use serde::Serialize;

#[derive(Serialize)]
struct Sample {
    name: &'static str,
    rows: Vec<Vec<f64>>,
    flat: Vec<u32>,
    empty: Vec<u32>,
    nested: std::collections::BTreeMap<String, f64>,
    none: std::collections::BTreeMap<String, f64>,
}

fn render<T: Serialize>(value: &T) -> String {
    let mut out = Vec::new();
    let mut ser = serde_json::Serializer::with_formatter(&mut out, RowsFormatter::default());
    value
        .serialize(&mut ser)
        .expect("writing to a Vec cannot fail");
    String::from_utf8(out).expect("serde_json writes utf-8")
}

#[test]
fn rows_inline_blocks_split_and_output_parses_back() {
    let sample = Sample {
        name: "a\"b",
        rows: vec![vec![1.0, -0.5], vec![2.25, 3.0]],
        flat: vec![1, 2, 3],
        empty: vec![],
        nested: [("x".to_string(), 1.5)].into_iter().collect(),
        none: Default::default(),
    };
    let text = render(&sample);
    let expected = "{\n  \"name\": \"a\\\"b\",\n  \"rows\": [\n    [1.0, -0.5],\n    [2.25, 3.0]\n  ],\n  \"flat\": [1, 2, 3],\n  \"empty\": [],\n  \"nested\": {\n    \"x\": 1.5\n  },\n  \"none\": {}\n}";
    assert_eq!(text, expected);
    let back: serde_json::Value = serde_json::from_str(&text).expect("output is valid json");
    assert_eq!(back["rows"][1][0], 2.25);
}
