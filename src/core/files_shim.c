/* File identity for flexmbs_core_files: two paths name the same file when
 * they resolve to the same device and inode, however they are spelled
 * (./s.nml, ../in/s.nml, a link). */
#include <sys/stat.h>

/* What a path names, links followed: 0 nothing, 1 a regular file, 2 a
 * folder, 3 anything else (a FIFO, a device, a socket). Reading a FIFO
 * blocks until some writer opens it, and a device may never end, so only
 * regular files are read as inputs or replaced as outputs. */
int flexmbs_file_kind(const char *path)
{
    struct stat s;
    if (stat(path, &s) != 0) return 0;
    if (S_ISREG(s.st_mode)) return 1;
    if (S_ISDIR(s.st_mode)) return 2;
    return 3;
}

/* 1 when both paths exist and are the same file, 0 otherwise. */
int flexmbs_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) != 0 || stat(b, &sb) != 0) return 0;
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

#include <unistd.h>

/* The machine's physical memory in bytes, or -1 when unknown. */
long long flexmbs_physical_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || size <= 0) return -1;
    return (long long)pages * (long long)size;
}
