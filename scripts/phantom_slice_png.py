# Mid-z slices of NRRD volumes (gzip, float) stacked into one greyscale PNG (window -1000..2200 HU); no numpy.
# Usage: python3 scripts/phantom_slice_png.py out.png Data/foam-phantom/pre.nrrd Data/foam-phantom/post.nrrd
import gzip, struct, zlib, sys
def read(p):
    b=open(p,'rb').read(); i=b.index(b'\n\n'); h=b[:i].decode(); d=gzip.decompress(b[i+2:])
    sz=[int(x) for x in [l for l in h.splitlines() if l.startswith('sizes:')][0].split()[1:]]
    return sz, struct.unpack('<%df'%(len(d)//4), d)
def png(path,w,h,rows):
    raw=b''.join(b'\x00'+bytes(r) for r in rows)
    def chunk(t,d): return struct.pack('>I',len(d))+t+d+struct.pack('>I',zlib.crc32(t+d)&0xffffffff)
    open(path,'wb').write(b'\x89PNG\r\n\x1a\n'+chunk(b'IHDR',struct.pack('>IIBBBBB',w,h,8,0,0,0,0))+chunk(b'IDAT',zlib.compress(raw))+chunk(b'IEND',b''))
rows=[]
for p in sys.argv[2:]:
    (nx,ny,nz),v=read(p); z=nz//2
    for y in range(ny):
        rows.append([max(0,min(255,int((v[(z*ny+y)*nx+x]+1000)/(3200)*255))) for x in range(nx)])
    w=nx
png(sys.argv[1],w,len(rows),rows)
