// Placeholder; the truth command arrives next.
int main() { return 0; }
