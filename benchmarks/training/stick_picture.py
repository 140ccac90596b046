#!/usr/bin/python3
"""One frame of a pose net's output over its input, as a PNG: the input's newest ON TORE plane
in grey, the true joints green, the predicted red, and the last stage's xy heatmaps of the right
hand and the right elbow in red over the next two panels.

    stick_picture.py RECORDING.yelan.h5 INPUT.h5 OUTPUT.h5 OUT.png [T_US [J,J]]

J,J: the two joints whose heatmaps are drawn (SPEC's order: 0 head, 1/2 shoulders R/L,
3/4 elbows, 5/6 hips, 7/8 hands, 9/10 knees, 11/12 feet); 7,3 (right hand, right elbow) unless given.

INPUT.h5: `input` (S x C x 130 x 173, the window ending at T_US, as `yelan model forward`
reads it); OUTPUT.h5: what `yelan model forward` wrote for it. The 2x2-downscaled sensor of the
shipped configs (346 x 260) is assumed.
"""
import h5py, numpy as np, zlib, struct, sys
def png(path, img):
    h,w,_=img.shape
    raw=b''.join(b'\x00'+img[y].tobytes() for y in range(h))
    def chunk(t,d): return struct.pack('>I',len(d))+t+d+struct.pack('>I',zlib.crc32(t+d)&0xffffffff)
    open(path,'wb').write(b'\x89PNG\r\n\x1a\n'+chunk(b'IHDR',struct.pack('>IIBBBBB',w,h,8,2,0,0,0))+chunk(b'IDAT',zlib.compress(raw))+chunk(b'IEND',b''))
rec, inpath, outp, pic = sys.argv[1:5]
t=int(sys.argv[5]) if len(sys.argv)>5 else 2000000
o=h5py.File(outp,'r'); f=h5py.File(rec,'r')
inp=h5py.File(inpath,'r')['input'][-1]   # 6 x 130 x 173
lt=f['labels/t'][()]; J=f['labels/joints'][()]; K=f['camera/K'][()]
j=J[np.searchsorted(lt,t)]
u=K[0,0]*j[:,0]/j[:,2]+K[0,2]; v=K[1,1]*j[:,1]/j[:,2]+K[1,2]
p=o['joints_norm'][-1]; pu=p[:,0]*173+173; pv=p[:,1]*130+130
S=2
base=np.clip(inp[0]*255,0,255).astype(np.uint8)           # 130 x 173 (input px = 2 sensor px)
img=np.repeat(np.repeat(base,2*S,0),2*S,1)               # sensor x S
img=np.stack([img]*3,-1).copy()
hm=o['heatmaps/stage1/xy'][-1]                           # 13 x 17 x 22 (stride 8) or 13 x 33 x 44 (stride 4)
cell=2*int(round(130/hm.shape[1]))                       # sensor px a heatmap cell
def heat(k):
    h=hm[k]/hm[k].max()
    big=np.repeat(np.repeat(h,cell*S,0),cell*S,1)[:260*S,:346*S]
    return big
panels=[img.copy()]
shown=tuple(int(k) for k in sys.argv[6].split(',')) if len(sys.argv)>6 else (7,3)
for k in shown:
    q=img.copy(); hb=heat(k)
    q[...,0]=np.clip(q[...,0]*0.5+hb*255,0,255); q[...,1]=(q[...,1]*0.5).astype(np.uint8); q[...,2]=(q[...,2]*0.5).astype(np.uint8)
    panels.append(q)
for q in panels:
    for k in range(13):
        for (x,y,c) in ((u[k],v[k],(0,255,0)),(pu[k],pv[k],(255,60,60))):
            X,Y=int(x*S),int(y*S)
            q[max(0,Y-3):Y+4,max(0,X-3):X+4]=c
png(pic, np.concatenate(panels,1).astype(np.uint8))
print('wrote',pic)
