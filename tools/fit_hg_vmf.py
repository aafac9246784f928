#!/usr/bin/env python3
# Fits a Henyey-Greenstein lobe of mean cosine g by a mixture of three von
# Mises-Fisher lobes about the same axis, minimising the chi-square
# divergence E[w^2] = int HG^2 / mixture (the second moment of the weight
# HG / mixture when directions are drawn from the mixture), and prints the
# table src/cache/product_sampler.cpp holds (HgAsVmf). Warm-started from
# g = 0.99 downwards so that the rows vary smoothly with g. Needs Debian's
# python3-numpy and python3-scipy; run with /usr/bin/python3.
import numpy as np
from scipy.optimize import minimize
c=np.concatenate([np.linspace(-1,0.9,4000,endpoint=False),1-np.geomspace(0.1,1e-7,6000)])
c=np.append(c,1.0)
def hg(g): return (1-g*g)/(4*np.pi*(1+g*g-2*g*c)**1.5)
def vmf(k):
    k=max(k,1e-4)
    return k/(2*np.pi*(-np.expm1(-2*k)))*np.exp(k*(c-1))
def chi(p,q): return np.trapz(p*p/q*2*np.pi,c)
n=3
def unpack(x):
    a=np.concatenate([x[:n-1],[0]]); w=np.exp(a)/np.exp(a).sum(); k=np.exp(x[n-1:])
    return w,k
gs=[0.99,0.97]+[round(0.05*i,2) for i in range(19,0,-1)]
x=np.array([np.log(0.6312/0.0798),np.log(0.289/0.0798)]+list(np.log([8762.54,389.677,4.379])))
rows=[]
for g in gs:
    p=hg(g)
    obj=lambda x: chi(p,sum(wi*vmf(ki) for wi,ki in zip(*unpack(x))))
    r=minimize(obj,x,method='Nelder-Mead',options={'maxiter':20000,'maxfev':20000,'xatol':1e-7,'fatol':1e-11})
    x=r.x
    w,k=unpack(x)
    rows.append((g,r.fun,w,k))
for g,f,w,k in sorted(rows):
    print(f"    {{{g:.2f}f, {{{w[0]:.5f}f, {w[1]:.5f}f, {w[2]:.5f}f}}, {{{k[0]:.5g}f, {k[1]:.5g}f, {k[2]:.5g}f}}}},  // E[w^2] {f:.5f}")
