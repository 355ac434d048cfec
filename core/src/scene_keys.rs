//! Where a key stands in a scene's TOML text: the dotted key whose value holds a byte
//! offset, the line of a dotted key, and toml's error message with both, so that every
//! scene error names its key and line.

/// toml's message with the line, and the dotted key whose value holds the error when toml
/// does not name it (a wrong type).
pub(crate) fn syntax_message(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().to_string();
    match e.span() {
        Some(span) => {
            let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
            match key_at(text, span.start) {
                Some(key)
                    if !msg.contains(&format!("`{}`", key.rsplit('.').next().unwrap_or(&key))) =>
                {
                    format!("line {line}: `{key}`: {msg}")
                }
                _ => format!("line {line}: {msg}"),
            }
        }
        None => msg,
    }
}

/// The dotted path of the innermost key whose value span contains byte `offset`. Every
/// entry is searched: a table opened by a `[header]` does not span its body.
fn key_at(text: &str, offset: usize) -> Option<String> {
    fn walk(
        value: &toml::de::DeValue,
        offset: usize,
        path: &str,
        best: &mut Option<(usize, String)>,
    ) {
        let mut visit = |span: std::ops::Range<usize>, child: &toml::de::DeValue, name: String| {
            if span.contains(&offset) && best.as_ref().is_none_or(|(len, _)| span.len() <= *len) {
                *best = Some((span.len(), name.clone()));
            }
            walk(child, offset, &name, best);
        };
        match value {
            toml::de::DeValue::Table(t) => {
                for (k, v) in t.iter() {
                    let name = if path.is_empty() {
                        k.get_ref().to_string()
                    } else {
                        format!("{path}.{}", k.get_ref())
                    };
                    visit(v.span(), v.get_ref(), name);
                }
            }
            toml::de::DeValue::Array(a) => {
                for (i, v) in a.iter().enumerate() {
                    visit(v.span(), v.get_ref(), format!("{path}[{i}]"));
                }
            }
            _ => {}
        }
    }
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut best = None;
    walk(
        &toml::de::DeValue::Table(root.into_inner()),
        offset,
        "",
        &mut best,
    );
    best.map(|(_, key)| key)
}

/// Line (1-based) of a dotted key path such as `tools[1].axis` in scene text.
pub fn key_line(text: &str, key: &str) -> Option<usize> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut span = root.span();
    let mut value: Option<&toml::de::DeValue> = None;
    let mut table = Some(root.get_ref());
    for part in key.split('.') {
        let (name, index) = match part.split_once('[') {
            Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        let t = match (table, value) {
            (Some(t), _) => t,
            (None, Some(toml::de::DeValue::Table(t))) => t,
            _ => break,
        };
        let Some((k, v)) = t.iter().find(|(k, _)| k.get_ref().as_ref() == name) else {
            break;
        };
        span = k.span();
        let mut cur = v.get_ref();
        if let (Some(i), toml::de::DeValue::Array(a)) = (index, cur) {
            match a.get(i) {
                Some(item) => {
                    span = item.span();
                    cur = item.get_ref();
                }
                None => break,
            }
        }
        value = Some(cur);
        table = None;
    }
    Some(text[..span.start.min(text.len())].matches('\n').count() + 1)
}
