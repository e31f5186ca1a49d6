"""scripts/screenshots.py, which takes the pictures of docs/dashboard.md, still works: run into a
temporary folder, each picture is a PNG of the browser window's size, with real content (not a blank
or error page: a page of one colour compresses to a few kB), and every picture the script writes is
the one docs/dashboard.md shows. Skips only when Chromium cannot start at all (as the script does)."""
import os
import struct
import subprocess
import sys
import tempfile

AXON = sys.argv[1]
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))


def png_size(path):
    with open(path, 'rb') as f:
        head = f.read(24)
    assert head[:8] == b'\x89PNG\r\n\x1a\n', '%s is not a PNG' % path
    return struct.unpack('>II', head[16:24])


def main():
    with tempfile.TemporaryDirectory() as out:
        p = subprocess.run([sys.executable, os.path.join(ROOT, 'scripts', 'screenshots.py'), '--axon', AXON, '--out', out],
                           capture_output=True, text=True, timeout=240)
        if p.stdout.startswith('SKIP'):
            print(p.stdout.strip())
            return 0
        assert p.returncode == 0, (p.returncode, p.stdout[-2000:], p.stderr[-3000:])
        written = [line.strip() for line in p.stdout.splitlines() if line.strip().endswith('.png')]
        assert len(written) >= 2, p.stdout
        shown = open(os.path.join(ROOT, 'docs', 'dashboard.md')).read()
        for path in written:
            w, h = png_size(path)
            size = os.path.getsize(path)
            print('%s: %dx%d, %d kB' % (os.path.basename(path), w, h, size // 1024))
            assert w >= 1000 and h >= 700, (path, w, h)
            assert size > 40 * 1024, '%s is %d bytes: a blank page?' % (path, size)
            assert 'images/%s' % os.path.basename(path) in shown, '%s is not in docs/dashboard.md' % path
    print('PASS')
    return 0


if __name__ == '__main__':
    sys.exit(main())
