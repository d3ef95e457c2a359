fn main() {
    let m = vkbrdf::material::presets::all();
    println!("{}", m.len());
}
