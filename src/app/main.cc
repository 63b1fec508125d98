// tailsim command line (placeholder until the commands are wired).
int main() { return 0; }
