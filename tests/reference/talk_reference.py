# An independent float64 implementation of the tracer conventions of docs/spec/tracer.md
# ("Conventions"; once the README's "The tracer"), written from the spec alone, not from
# rayreel's code. It rendered talk_160x90.png, which tests/render.rs compares with rayreel
# pixel for pixel.
# Usage: python3 talk_reference.py 160x90   (needs numpy and Pillow; writes ref_160x90.png)
import math, sys, numpy as np
from PIL import Image
def sub(a,b): return (a[0]-b[0],a[1]-b[1],a[2]-b[2])
def add(a,b): return (a[0]+b[0],a[1]+b[1],a[2]+b[2])
def mul(a,s): return (a[0]*s,a[1]*s,a[2]*s)
def dot(a,b): return a[0]*b[0]+a[1]*b[1]+a[2]*b[2]
def had(a,b): return (a[0]*b[0],a[1]*b[1],a[2]*b[2])
def norm(a):
    l=math.sqrt(dot(a,a)); return (a[0]/l,a[1]/l,a[2]/l)
M={'red':((0.1,0,0),(0.7,0,0),(1,1,1),100,0.5),'purple':((0.1,0,0.1),(0.7,0,0.7),(1,1,1),100,0.5),
   'green':((0,0.1,0),(0,0.6,0),(1,1,1),100,0.5),'floor':((0.1,0.1,0.1),(0.6,0.6,0.6),(1,1,1),100,0.5)}
S=[((-0.2,0,-1),0.7,'red'),((0.1,-0.3,0),0.1,'purple'),((-0.3,0,0),0.15,'green'),((0,-9000,0),8999.3,'floor')]
EPS=float(sys.argv[2]) if len(sys.argv)>2 else 1e-9
LP=(5,5,5); LA=LD=LS=(1,1,1); CAM=(0,0,1); MAXD=3
def isect(o,d,c,r):
    oc=sub(o,c); b=dot(oc,d); cc=dot(oc,oc)-r*r; disc=b*b-cc
    if disc<0: return None
    sq=math.sqrt(disc)
    q=-b-sq if b>0 else -b+sq   # stable: roots q and cc/q
    t1,t2=(q,cc/q) if q!=0 else (0.0,0.0)
    t1,t2=min(t1,t2),max(t1,t2)
    if t1>0: return t1
    if t2>0: return t2
    return None
def nearest(o,d,skip):
    best=None
    for k,(c,r,m) in enumerate(S):
        if k==skip: continue
        t=isect(o,d,c,r)
        if t is not None and (best is None or t<best[0]): best=(t,k)
    return best
def trace(o,d):
    col=(0.,0.,0.); w=1.0; skip=-1
    for depth in range(MAXD):
        h=nearest(o,d,skip)
        if h is None: break
        t,k=h; c,r,mn=S[k]; ka,kd,ks,sh,refl=M[mn]
        P=add(o,mul(d,t)); N=norm(sub(P,c))
        if dot(N,d)>0: N=mul(N,-1)
        i=had(ka,LA)
        Lv=sub(LP,P); dist=math.sqrt(dot(Lv,Lv)); L=mul(Lv,1/dist)
        so=add(P,mul(N,EPS))
        sv=sub(LP,so); sd=math.sqrt(dot(sv,sv)); sdir=mul(sv,1/sd)
        blocked=False
        for kk,(c2,r2,_) in enumerate(S):
            tt=isect(so,sdir,c2,r2)
            if tt is not None and tt<sd: blocked=True; break
        if not blocked:
            nl=dot(N,L)
            i=add(i,mul(had(kd,LD),max(0.,nl)))
            if nl>0:
                H=norm(add(L,mul(d,-1)))
                i=add(i,mul(had(ks,LS),max(0.,dot(N,H))**(sh/4)))
        col=add(col,mul(i,w)); w*=refl
        d=norm(sub(d,mul(N,2*dot(d,N)))); o=P; skip=k
    return col
def render(W,H):
    img=np.zeros((H,W,3)); 
    for i in range(H):
        for j in range(W):
            x=-1+2*(j+0.5)/W; y=(1-2*(i+0.5)/H)*H/W
            img[i,j]=trace(CAM,norm(sub((x,y,0),CAM)))
    return img
if __name__=='__main__':
    W,H=map(int,sys.argv[1].split('x'))
    img=render(W,H)
    out=np.round(255*np.clip(img,0,1)).astype(np.uint8)
    Image.fromarray(out).save(f'ref_{W}x{H}.png')
    try:
        rr=np.asarray(Image.open(f'rayreel_{W}x{H}_0000.png').convert('RGB')).astype(int)
    except FileNotFoundError:
        sys.exit(0)
    diff=np.abs(rr-out.astype(int))
    px=np.argwhere(diff.max(axis=2)>0)
    print(f'{W}x{H}: channels differ {int((diff>0).sum())}, pixels differ {len(px)}, max abs {diff.max()}')
    for (a,b) in px[:40]:
        print(a,b,'rayreel',rr[a,b],'ref',out[a,b],'ref255',np.round(255*img[a,b],4))
