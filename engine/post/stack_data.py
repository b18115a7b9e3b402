"""A post stack as plain data (for presets), and its validation. No bpy.

``stack_data`` reads a stack (``scene.penumbra.layers`` or any objects with the same fields)
into a JSON-ready dict; ``validate`` checks such a dict completely before anything is changed:
an unknown effect or a malformed value is an error (nothing is applied), an unknown field is
reported and skipped, a missing field keeps its default.
"""

FORMAT = 1
LAYER_FIELDS = ("effect", "name", "enabled", "solo", "mix")


def _plain(param, value):
    if param.type == "IMAGE":
        return value.name if value is not None else None
    if param.type == "COLOR":
        return [round(float(v), 6) for v in value]
    if param.type == "FLOAT":
        return round(float(value), 6)
    return value


def stack_data(layers, effects):
    """{"format": 1, "layers": [...]} of ``layers`` in stack order."""
    out = []
    for layer in layers:
        group = layer.params()
        params = {p.name: _plain(p, getattr(group, p.name)) for p in effects[layer.effect].params}
        out.append(
            {
                "effect": layer.effect,
                "name": layer.name,
                "enabled": bool(layer.enabled),
                "solo": bool(layer.solo),
                "mix": round(float(layer.mix), 6),
                "params": params,
            }
        )
    return {"format": FORMAT, "layers": out}


def _check(param, value):
    """``value`` for ``param`` from preset data, or raise ValueError."""
    kind = param.type
    if kind == "IMAGE":
        if value is not None and not isinstance(value, str):
            raise ValueError("expected an image name or null")
        return value
    if kind == "BOOL":
        if not isinstance(value, bool):
            raise ValueError("expected true or false")
        return value
    if kind == "ENUM":
        return param.clamp(value)
    if kind == "COLOR":
        if not isinstance(value, (list, tuple)) or len(value) != len(param.default):
            raise ValueError(f"expected a list of {len(param.default)} numbers")
        return tuple(param.clamp(value))
    if kind == "INT" and (isinstance(value, bool) or not isinstance(value, int)):
        raise ValueError("expected a whole number")
    if kind == "FLOAT" and (isinstance(value, bool) or not isinstance(value, (int, float))):
        raise ValueError("expected a number")
    return param.clamp(value)


def validate(data, effects):
    """(layers, errors, warnings). ``layers`` is a list of {field: value, "params": {...}}
    ready to apply when ``errors`` is empty."""
    errors, warnings, layers = [], [], []
    if not isinstance(data, dict) or not isinstance(data.get("layers"), list):
        return [], ["not a post-stack preset (no layer list)"], []
    if data.get("format", FORMAT) > FORMAT:
        warnings.append(f"written by a newer Penumbra (format {data['format']}); unknown fields are skipped")
    for index, raw in enumerate(data["layers"], 1):
        where = f"layer {index}"
        if not isinstance(raw, dict):
            errors.append(f"{where}: not a layer")
            continue
        effect = raw.get("effect")
        if effect not in effects:
            errors.append(f"{where}: unknown effect {effect!r}; expected one of {', '.join(effects)}")
            continue
        cls = effects[effect]
        layer = {"effect": effect, "params": {}}
        for key in raw:
            if key not in LAYER_FIELDS and key != "params":
                warnings.append(f"{where} ({effect}): unknown field {key!r} skipped")
        if not isinstance(raw.get("name", ""), str):
            errors.append(f"{where}: name must be text")
        layer["name"] = raw.get("name", cls.label)
        for key in ("enabled", "solo"):
            value = raw.get(key, key == "enabled")
            if not isinstance(value, bool):
                errors.append(f"{where}: {key} must be true or false")
            layer[key] = value
        mix = raw.get("mix", 1.0)
        if isinstance(mix, bool) or not isinstance(mix, (int, float)):
            errors.append(f"{where}: mix must be a number")
        else:
            layer["mix"] = min(max(float(mix), 0.0), 1.0)
        declared = {p.name: p for p in cls.params}
        params = raw.get("params", {})
        if not isinstance(params, dict):
            errors.append(f"{where}: params must be a mapping")
            params = {}
        for name, value in params.items():
            if name not in declared:
                warnings.append(f"{where} ({effect}): unknown parameter {name!r} skipped")
                continue
            try:
                layer["params"][name] = _check(declared[name], value)
            except ValueError as exc:
                errors.append(f"{where} ({effect}): {name}: {exc}")
        layers.append(layer)
    return layers, errors, warnings
