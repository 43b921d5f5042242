// Owner of the tests' precompiled header (cmake/BuildSpeed.cmake).
int main() { return 0; }
