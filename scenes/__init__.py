"""Built-in scenes: TOML files in this folder, loadable by name with
`world.loader.load_scene("living_room")`. Assets they use live in `assets/`;
`make_assets.py` regenerates them."""
