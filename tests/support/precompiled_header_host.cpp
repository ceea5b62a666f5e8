// The target that owns the tests' precompiled header (tests/CMakeLists.txt): an executable, so
// that it compiles with the tests' own flags (-fPIE), and so that it runs it does nothing.
int main() {
    return 0;
}
