#!/usr/bin/env python3
"""Front and side views of OBJ meshes in one PNG (matplotlib), for a quick look at bodies.

Usage: python3 tools/preview_obj.py out.png a.obj [b.obj ...]
"""
import sys, numpy as np, matplotlib
matplotlib.use('Agg'); import matplotlib.pyplot as plt
from matplotlib.collections import PolyCollection
def load(p):
    V=[];F=[]
    for l in open(p):
        if l.startswith('v '): V.append([float(x) for x in l.split()[1:4]])
        elif l.startswith('f '): F.append([int(x)-1 for x in l.split()[1:4]])
    return np.array(V), np.array(F)
files=sys.argv[2:]; fig,axes=plt.subplots(2,len(files),figsize=(4*len(files),8))
axes=np.array(axes).reshape(2,-1)
for i,f in enumerate(files):
    V,F=load(f)
    for r,(a,b,d,sgn) in enumerate([(0,1,2,1),(2,1,0,-1)]):
        ax=axes[r,i]; T=V[F]; n=np.cross(T[:,1]-T[:,0],T[:,2]-T[:,0]); n/=np.linalg.norm(n,axis=1,keepdims=True)+1e-12
        depth=T[:,:,d].mean(1)*sgn; o=np.argsort(depth)
        light=np.clip(n[:,d]*sgn,0,1)*0.8+0.2; vis=n[:,d]*sgn>-0.2
        polys=T[o][:,:,[a,b]]; 
        if r==1: polys[:,:,0]*=-1
        pc=PolyCollection(polys,facecolors=plt.cm.gray(light[o]),edgecolors='none'); ax.add_collection(pc)
        ax.set_xlim(-1,1); ax.set_ylim(-1.3,0.9); ax.set_aspect('equal'); ax.set_title(f.split('/')[-1]+(' front' if r==0 else ' side'),fontsize=8)
plt.tight_layout(); plt.savefig(sys.argv[1],dpi=70)
