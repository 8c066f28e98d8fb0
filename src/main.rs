fn main() {
    println!("cellsim: the command-line interface is not built yet");
}
